"""Smoke test of the benchmark runner's quick mode, the stages that time other processes: the start-up
of a fresh interpreter and of `verify`, the language server, and the generated ROS 1 nodes' monitors
(tests/benchmark_quick.py). A file of its own, so that pytest-xdist runs it beside the others."""
from __future__ import annotations

import pytest

from tests.benchmark_quick import run_group


@pytest.mark.slow
@pytest.mark.usefixtures("live_processes_alone")
def test_quick_mode_process_stages(tmp_path, capsys):
    by_stage, table = run_group("processes", tmp_path, capsys)
    assert all(r["result"]["exit"] == 0 for name in ("startup-python", "startup-help", "startup-check",
                                                     "startup-analyze") for r in by_stage[name])
    for r in by_stage.get("lsp-keystroke", []):  # (unavailable without pygls: a failure under CI, above)
        assert "analysed (median)" in r["result"]
    assert "| startup-python | 1 |" in table
