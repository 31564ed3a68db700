"""``prove --format sarif``: the proof's diagnostics (or why the input is invalid) as a SARIF 2.1.0 log on
standard output (``verify.outputs.sarif``), and as text on standard error."""
from __future__ import annotations

import json

from .sarif import to_sarif
from . import Output, Report
from .diagnostics_text import render as diagnostics


def render(report: Report) -> Output:
    log = to_sarif(list(report.diagnostics), report.sources)
    return Output(json.dumps(log, indent=2) + "\n", diagnostics(report).stderr)
