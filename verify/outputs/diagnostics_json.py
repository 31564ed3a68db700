"""Diagnostics as one JSON document, schema ``verify.diagnostics/1`` (``verify.outputs.rendering``)."""
from __future__ import annotations

import json
from typing import Any

from .rendering import diagnostics_json
from . import Output, Report


def render(report: Report) -> Output:
    doc = diagnostics_json(report.diagnostics)
    doc.update(report.extra.get("json", {}))
    return Output(stdout=json.dumps(doc, indent=2, sort_keys=False) + "\n")


def with_diagnostics(doc: dict[str, Any], report: Report) -> Output:
    """A command's result document with the report's diagnostics as ``verify.diagnostics/1`` items."""
    doc["diagnostics"] = diagnostics_json(report.diagnostics)["diagnostics"]
    return Output(json.dumps(doc, indent=2) + "\n")
