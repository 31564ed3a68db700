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
where the regular full collections see it like any other long-lived data. Nothing is kept from
collection: garbage cycles among these objects are found by the next full collection. This is skipped
while the program has frozen objects of its own (``gc.freeze`` before a fork), which must stay frozen.
"""
from __future__ import annotations

import gc
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def paused_gc() -> Iterator[None]:
    """Disable the cyclic garbage collector inside the block (re-entrant; the previous state returns).
    Leaving the outermost pause moves what survived it to the oldest generation (see above)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            _promote_survivors()
            gc.enable()


def _promote_survivors() -> None:
    """Move every object the collector tracks to its oldest generation without traversing them."""
    if gc.get_freeze_count() == 0:
        gc.freeze()
        gc.unfreeze()
