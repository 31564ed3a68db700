"""Diagnostics as one JSON document, schema ``verify.diagnostics/1`` (``verify.outputs.rendering``)."""
from __future__ import annotations

import json

from .rendering import diagnostics_json
from . import Output, Report


def render(report: Report) -> Output:
    doc = diagnostics_json(report.diagnostics)
    doc.update(report.extra.get("json", {}))
    return Output(stdout=json.dumps(doc, indent=2, sort_keys=False) + "\n")
