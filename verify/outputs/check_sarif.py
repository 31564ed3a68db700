"""``check --format sarif``: the diagnostics as a SARIF 2.1.0 log, for code scanning."""
from __future__ import annotations

from .diagnostics_sarif import render  # noqa: F401 - the same log
