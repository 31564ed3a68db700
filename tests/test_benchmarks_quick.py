"""Smoke test of the benchmark runner's quick mode, the stages that run in its own process: parsers,
analyses, the hostile inputs, prove, synthesis and its baselines (tests/benchmark_quick.py)."""
from __future__ import annotations

import pytest

from tests.benchmark_quick import run_group


@pytest.mark.slow
def test_quick_mode_in_process_stages(tmp_path, capsys):
    by_stage, table = run_group("in-process", tmp_path, capsys)
    assert [r["tasks"] for r in by_stage["parse+check"]] == [10, 30]
    assert "| parse+check | 10 |" in table and "| prove-exact | 4 | 1 |" in table
