"""``trace --format json``: schema ``verify.trace/1`` (``verify.trace.report``), the findings as
``verify.diagnostics/1`` items."""
from __future__ import annotations

import json

from .rendering import diagnostics_json
from . import Output, Report
from .diagnostics_json import render as diagnostics


def render(report: Report) -> Output:
    if report.result is None:
        return diagnostics(report)
    from ..trace.report import to_json

    doc = to_json(report.result)
    doc["diagnostics"] = diagnostics_json(report.diagnostics)["diagnostics"]
    return Output(json.dumps(doc, indent=2) + "\n")
