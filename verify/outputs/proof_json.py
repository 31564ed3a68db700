"""``prove --format json``: one document, schema ``verify.proof/1`` (``verify.prove.report``); for invalid
input the same schema with no verdicts, the diagnostics and exit code 2."""
from __future__ import annotations

import json
from typing import Any

from .rendering import diagnostics_json
from ..prove.report import SCHEMA, to_json
from . import Output, Report


def render(report: Report) -> Output:
    if report.result is None:
        doc: dict[str, Any] = {"schema": SCHEMA, "system": None, "verdicts": []}
        doc.update(diagnostics_json(report.diagnostics))
        doc["exit_code"] = 2
    else:
        doc = to_json(report.model, report.result)
    return Output(json.dumps(doc, indent=2) + "\n")
