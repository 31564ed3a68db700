"""The garbage collector paused while the pipeline builds its long-lived objects.

Loading a 10,000-task system allocates millions of objects (tokens, typed nodes, spans, model objects)
that all stay alive, and CPython's cyclic collector, triggered by allocation counts, traverses the
growing older generations again and again: two thirds of the load time went to it. The front end and
the analysis create no garbage cycles worth collecting while they run, so their entry points pause the
collector and restore its previous state afterwards (reference counting still frees what is dropped).
"""
from __future__ import annotations

import gc
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def paused_gc() -> Iterator[None]:
    """Disable the cyclic garbage collector inside the block (re-entrant; the previous state returns)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
