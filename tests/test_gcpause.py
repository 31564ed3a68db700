"""The collector paused while the pipeline runs (``verify.core.gcpause``) still finds the garbage cycles made
in the pauses: a long process (an editor's language server, a fuzzer) does not grow without bound."""
from __future__ import annotations

import gc

import pytest
import verify
from verify.core import gcpause

BROKEN = "component A {\n  task T { wcet 1 ms }\nsystem S { instance x : Nope }\n"  # (Lark's error path)


def _garbage_per_load() -> int:
    gc.collect()
    gc.set_debug(gc.DEBUG_SAVEALL)
    try:
        verify.load_text(BROKEN)
        gc.collect()
        return len(gc.garbage)
    finally:
        gc.garbage.clear()
        gc.set_debug(0)


@pytest.mark.slow
def test_repeated_loads_stay_bounded(monkeypatch):
    per_load = _garbage_per_load()
    assert per_load > 20  # the error path makes cycles: without collections they would pile up
    monkeypatch.setattr(gcpause, "FULL_COLLECTION_FLOOR", 50_000, raising=False)
    gc.collect()
    start = len(gc.get_objects())
    loads = 1000  # (without the collections, about 100 tracked objects more per load: 100,000)
    peak = 0
    for i in range(loads):
        verify.load_text(BROKEN)
        if i % 25 == 0:
            peak = max(peak, len(gc.get_objects()))
    # a full collection once the pauses made as many objects as there were: never much more than twice the start
    assert peak < 2 * start + 10_000, (per_load, loads, start, peak)
