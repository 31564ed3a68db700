"""Smoke test of the benchmark runner's quick mode, the ``tightness`` stage (tests/benchmark_quick.py):
every part of it runs (drawn systems with and without user bounds, the AND-join shape, the Autoware
example) and no run is above its bound (else an error row), with the quick search budgets
(``benchmarks/tightness.py``). A file of its own, so that pytest-xdist runs it beside the others."""
from __future__ import annotations

import pytest

from tests.benchmark_quick import run_group


@pytest.mark.slow
def test_quick_mode_tightness(tmp_path, capsys):
    by_stage, _ = run_group("tightness", tmp_path, capsys)
    (row,) = by_stage["tightness"]
    result = row["result"]
    assert result["random systems"] == result["AND systems"] == 4
    for part in ("random", "random without user bounds", "AND", "Autoware"):
        for metric in ("reaction_time", "data_age"):
            assert result[f"{part} {metric}"].startswith("bounded "), (part, metric, result[f"{part} {metric}"])
