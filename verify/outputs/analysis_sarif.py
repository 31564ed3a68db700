"""``analyze --format sarif``: the analysis' diagnostics (or why the input is invalid) as a SARIF 2.1.0
log, for code scanning (``verify.outputs.sarif``)."""
from __future__ import annotations

from .diagnostics_sarif import render  # noqa: F401 - the same log
