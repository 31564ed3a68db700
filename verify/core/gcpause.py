"""The garbage collector paused while the pipeline builds its long-lived objects.

Loading a 10,000-task system allocates millions of objects (tokens, typed nodes, spans, model objects)
that all stay alive, and CPython's cyclic collector, triggered by allocation counts, traverses the
growing older generations again and again: two thirds of the load time went to it. The front end, the
analysis and the proof create no garbage cycles worth collecting while they run, so their entry points
pause the collector and restore its previous state afterwards (reference counting still frees what is
dropped).

Re-enabling the collector alone would leave every object made in the pause in the youngest generation,
to be traversed by the next young collection (a million objects after a 10,000-task load: a quarter of
a second, at whatever allocation happens to come next) and again by the middle one. What survives a
pause is the result (a project, a model, an analysis) and lives on, so the outermost pause hands it to
the oldest generation directly (``gc.freeze`` then ``gc.unfreeze``: two list splices, no traversal),
where the regular full collections see it like any other long-lived data. This is skipped while the
program has frozen objects of its own (``gc.freeze`` before a fork), which must stay frozen.

Objects moved this way do not count towards the collector's own trigger of a full collection (the
oldest generation grew by a quarter), so garbage cycles made inside pauses — Lark's error path,
networkx views, Z3 references and exception tracebacks make plenty — would never be found in a long
process (an editor's language server, a fuzzer, a library loading many models: 80 MB more per 1,000
loads). So the outermost pause runs a full collection itself when the pauses since the previous one
have made more tracked objects than the collector tracked after it, and at least
``FULL_COLLECTION_FLOOR``: garbage stays bounded, the cost of the collections is amortised over the
work that made the objects, and a single command on a 10,000-task model (1.6 million objects tracked at
its end) never pays one. What a pause made is the growth of the collector's own allocation count
(``gc.get_count()[0]``: tracked objects allocated less those freed, which nothing resets while the
collector is disabled) — read in constant time, where counting the tracked objects walks all of them.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager
from collections.abc import Iterator


@contextmanager
def paused_gc() -> Iterator[None]:
    """Disable the cyclic garbage collector inside the block (re-entrant; the previous state returns).
    Leaving the outermost pause moves what survived it to the oldest generation (see above)."""
    enabled = gc.isenabled()
    gc.disable()
    at_start = gc.get_count()[0]
    try:
        yield
    finally:
        if enabled:
            _promote_survivors(max(0, gc.get_count()[0] - at_start))
            gc.enable()


#: a full collection runs only when the pauses since the last one made more objects than this (see above)
FULL_COLLECTION_FLOOR = 2_000_000
_after_last_full = [0]  # objects tracked after the last full collection run here
_made = [0]  # tracked objects the outermost pauses made since then


def _promote_survivors(made: int) -> None:
    """Move every object the collector tracks to its oldest generation without traversing them, and
    run a full collection when the pauses since the last one made more objects than it left (see above)."""
    if gc.get_freeze_count() != 0:
        return
    gc.freeze()
    gc.unfreeze()
    _made[0] += made
    if _made[0] > max(_after_last_full[0], FULL_COLLECTION_FLOOR):
        gc.collect()
        gc.freeze()
        _after_last_full[0] = gc.get_freeze_count()  # (a walk of every object, after a collection that walked them)
        gc.unfreeze()
        _made[0] = 0
