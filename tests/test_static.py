"""Static checks that run with the test suite (and so in `.ci/run`): mypy, strict on `verify/`, and ruff on the
whole repository, both with the settings in pyproject.toml. Both tools come with the test extras; a missing
one fails the run (it is never skipped)."""
from __future__ import annotations

import pytest

import os
import subprocess
import sys
from pathlib import Path

pytestmark = pytest.mark.slow  # (the quick loop leaves it out: docs/contributing/tests.md)

ROOT = Path(__file__).resolve().parent.parent


def _run(*command: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", *command], cwd=ROOT, capture_output=True, text=True,
                          env=dict(os.environ, MYPY_FORCE_COLOR="0", NO_COLOR="1"))


def test_mypy_strict_on_the_package():
    proc = _run("mypy", "--no-error-summary")  # files and strictness: [tool.mypy] in pyproject.toml
    assert "No module named mypy" not in proc.stderr, "mypy is missing: install the test extras"
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]


def test_ruff_finds_nothing():
    proc = _run("ruff", "check", "--output-format", "concise", ".")
    assert "No module named ruff" not in proc.stderr, "ruff is missing: install the test extras"
    assert proc.returncode == 0, proc.stdout[-6000:] + proc.stderr[-2000:]


def test_the_package_says_it_is_typed():
    assert (ROOT / "verify" / "py.typed").is_file()
