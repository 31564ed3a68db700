"""Diagnostics as a SARIF 2.1.0 log, for code scanning (``verify.outputs.sarif``)."""
from __future__ import annotations

import json

from .sarif import to_sarif
from . import Output, Report


def render(report: Report) -> Output:
    return Output(stdout=json.dumps(to_sarif(list(report.diagnostics), report.sources), indent=2) + "\n")
