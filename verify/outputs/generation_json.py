"""``verify gen --format json``: one ``verify.gen/1`` document."""
from __future__ import annotations

import json

from . import Output, Report


def render(report: Report) -> Output:
    outcome = report.result
    doc = {"schema": "verify.gen/1", "target": report.extra["target"], "system": report.model.name,
           "directory": report.extra["directory"], "written": outcome.written, "unchanged": outcome.unchanged,
           "kept": outcome.kept}
    return Output(stdout=json.dumps(doc, indent=2) + "\n")
