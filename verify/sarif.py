"""SARIF 2.1.0 logs of diagnostics (of `prove` and `check`), for code scanning (specs/proof.md §9).

One run, tool driver "verify" whose rules are the diagnostic codes used (in code order); one result
per diagnostic: ``level`` from the severity, the primary location at the diagnostic's span (for a
violated spec: the spec in the DSL), ``relatedLocations`` for its secondary labels (the chain's
hops), notes and help appended to the message. URIs are relative to the working directory with
forward slashes (percent-encoded); a file outside it gets an absolute ``file:`` URI. The output is
deterministic (no timestamps; no absolute paths for files below the working directory).
"""
from __future__ import annotations

import os
import pathlib
import re
from typing import Any
from urllib.parse import quote

from . import __version__ as VERSION
from .codes import CODES, spec_anchor
from .diagnostics import Diagnostic, Severity
from .source import Span

SCHEMA_URI = "https://json.schemastore.org/sarif-2.1.0.json"
LEVELS = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.NOTE: "note"}


def _uri(path: str) -> str:
    """A URI reference for ``path``: relative to the working directory when the file lies below it
    (forward slashes, percent-encoded as RFC 3986 asks, e.g. a space as ``%20``), else an absolute
    ``file:`` URI (a ``../`` path would point outside the repository that code scanning resolves
    relative URIs against)."""
    if not (os.path.isabs(path) or os.path.exists(path)):
        return quote(path.replace(os.sep, "/"), safe="/")  # a name that is no file (``<text>``)
    absolute = os.path.abspath(path)
    rel = os.path.relpath(absolute)
    if rel == os.pardir or rel.startswith(os.pardir + os.sep) or os.path.isabs(rel):
        return pathlib.Path(absolute).as_uri()
    return quote(rel.replace(os.sep, "/"), safe="/")


def _location(span: Span, message: str | None = None, ident: int | None = None) -> dict[str, Any]:
    region = {"startLine": max(span.line, 1), "startColumn": max(span.column, 1)}
    if span.end_line >= span.line and span.end_line > 0:
        region["endLine"] = span.end_line
        if span.end_column > 0 and (span.end_line > span.line or span.end_column > span.column):
            region["endColumn"] = span.end_column
    loc: dict[str, Any] = {"physicalLocation": {"artifactLocation": {"uri": _uri(span.file)}, "region": region}}
    if ident is not None:
        loc["id"] = ident
    if message:
        loc["message"] = {"text": message}
    return loc


def _rule_name(title: str) -> str:
    return "".join(w.capitalize() for w in re.findall(r"[A-Za-z0-9]+", title))


def to_sarif(diagnostics: list[Diagnostic] | tuple[Diagnostic, ...]) -> dict[str, Any]:
    codes = sorted({d.code for d in diagnostics})
    rules = [{"id": c, "name": _rule_name(CODES[c].title), "shortDescription": {"text": CODES[c].title},
              "fullDescription": {"text": f"{CODES[c].title}; explained in {spec_anchor(c)} "
                                          f"(`verify explain {c}`)"},
              "defaultConfiguration": {"level": LEVELS[CODES[c].severity]},
              "help": {"text": f"Run `verify explain {c}` for the meaning and a minimal failing example."}}
             for c in codes]
    index = {c: i for i, c in enumerate(codes)}
    results = []
    for d in diagnostics:
        text = d.message
        if d.primary.message:
            text += f" ({d.primary.message})"
        extra = [f"note: {n}" for n in d.notes] + ([f"help: {d.help}"] if d.help else [])
        if extra:
            text += "\n" + "\n".join(extra)
        result = {"ruleId": d.code, "ruleIndex": index[d.code], "level": LEVELS[d.severity],
                  "message": {"text": text}, "locations": [_location(d.primary.span)]}
        if d.secondary:
            result["relatedLocations"] = [_location(lb.span, lb.message or "related", n)
                                          for n, lb in enumerate(d.secondary, 1)]
        results.append(result)
    return {
        "$schema": SCHEMA_URI,
        "version": "2.1.0",
        "runs": [{
            "tool": {"driver": {"name": "verify", "version": VERSION, "semanticVersion": VERSION,
                                "rules": rules}},
            "columnKind": "unicodeCodePoints",
            "results": results,
        }],
    }
