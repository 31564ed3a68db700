"""``trace --format sarif``: the findings (or why the input is invalid) as a SARIF 2.1.0 log
(``verify.outputs.sarif``), for code scanning."""
from __future__ import annotations

from .diagnostics_sarif import render  # noqa: F401 - the same log
