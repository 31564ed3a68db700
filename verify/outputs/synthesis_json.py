"""``synth --format json``: one document, schema ``verify.synth/1`` (``verify.synth.report``)."""
from __future__ import annotations

import json

from ..synth.report import SCHEMA, to_json
from . import Output, Report
from .diagnostics_json import with_diagnostics


def render(report: Report) -> Output:
    extra = report.extra
    if extra.get("dsl") is not None:
        doc = to_json(report.result, report.file, dsl=extra["dsl"], diff=extra.get("diff"),
                      written=extra.get("written"))
    else:
        doc = (to_json(report.result, report.file) if report.result is not None
               else {"schema": SCHEMA, "file": report.file, "status": "invalid"})
        return with_diagnostics(doc, report)
    return Output(json.dumps(doc, indent=2) + "\n")
