"""``analyze --format json``: schema ``verify.analysis/1`` (``verify.timing.report``), the problems as
``verify.diagnostics/1`` items."""
from __future__ import annotations

import json

from .rendering import diagnostics_json
from ..timing.report import to_json
from . import Output, Report
from .diagnostics_json import render as diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    doc = to_json(report.result)
    doc["diagnostics"] = diagnostics_json(report.diagnostics)["diagnostics"]
    return Output(json.dumps(doc, indent=2) + "\n")
