"""Shared test fixtures."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@pytest.fixture
def write(tmp_path):
    """Write files into a temporary project directory; returns the path of the first one."""

    def _write(files: dict[str, str | bytes]) -> str:
        first = None
        for name, content in files.items():
            path = tmp_path / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                path.write_bytes(content)
            else:
                path.write_text(content, encoding="utf-8")
            first = first or str(path)
        return first

    return _write


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() in ("1", "true", "yes")


def pytest_terminal_summary(terminalreporter):
    """Report the tightness of the analytic bounds against the simulator (tests/test_bounds_vs_simulation)."""
    import sys

    module = sys.modules.get("tests.test_bounds_vs_simulation")
    lines = module.tightness_summary() if module else []
    if lines:
        terminalreporter.section("tightness of the analytic bounds (simulated worst / bound)")
        for line in lines:
            terminalreporter.write_line(line)
