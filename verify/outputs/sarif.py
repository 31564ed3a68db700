"""SARIF 2.1.0 logs of diagnostics (of `check`, `analyze` and `prove`), for code scanning (specs/proof.md §9).

One run, tool driver "verify" whose rules are the diagnostic codes used (in code order), each with the
text of ``verify explain CODE`` as its help (plain and Markdown) and, when the installed distribution
names its documentation (``[project.urls] Documentation``), a ``helpUri`` to that section; one result
per diagnostic: ``level`` from the severity, the primary location at the diagnostic's span (for a
violated spec: the spec in the DSL), ``relatedLocations`` for its secondary labels (the chain's
hops), notes and help appended to the message, and ``partialFingerprints`` that stay the same when
lines are added above it (``verifyFingerprint/v1``: the code, the file and the text of the primary
line, numbered among equal ones). URIs are relative to the working directory with
forward slashes (percent-encoded); a file outside it gets an absolute ``file:`` URI. The output is
deterministic (no timestamps; no absolute paths for files below the working directory). Message texts
are shown as the text renderer shows them (``verify.core.sanitize.shown``: no control character, no line
break from a name; notes and help each on a line of their own).
"""
from __future__ import annotations

import functools
import hashlib
import os
import pathlib
import re
from collections.abc import Mapping
from typing import Any
from urllib.parse import quote

from .. import __version__ as VERSION
from ..core.codes import CODES, spec_anchor
from ..core.diagnostics import Diagnostic, Severity
from ..core.explain import explain
from ..core.sanitize import shown
from ..core.source import SourceFile, Span

SCHEMA_URI = "https://json.schemastore.org/sarif-2.1.0.json"
LEVELS = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.NOTE: "note"}


def _uri(path: str) -> str:
    """A URI reference for ``path``: relative to the working directory when the file lies below it
    (forward slashes, percent-encoded as RFC 3986 asks, e.g. a space as ``%20``), else an absolute
    ``file:`` URI (a ``../`` path would point outside the repository that code scanning resolves
    relative URIs against). Worked out once per path and working directory in one log (a log of 32,000
    results names a few files)."""
    return _uri_from(path, os.getcwd())


@functools.lru_cache(maxsize=256)
def _uri_from(path: str, cwd: str) -> str:
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
        loc["message"] = {"text": shown(message)}
    return loc


def _rule_name(title: str) -> str:
    return "".join(w.capitalize() for w in re.findall(r"[A-Za-z0-9]+", title))


def documentation_uri() -> str | None:
    """The documentation URL the installed distribution names (``Project-URL: Documentation``), if any."""
    from importlib.metadata import PackageNotFoundError, metadata

    try:
        urls = metadata("verify-timing").get_all("Project-URL") or []
    except PackageNotFoundError:
        return None
    return next((u.split(",", 1)[1].strip() for u in urls if u.split(",", 1)[0].strip().lower() == "documentation"),
                None)


def _rule(code: str, docs: str | None) -> dict[str, Any]:
    title = CODES[code].title
    section = explain(code)
    rule: dict[str, Any] = {
        "id": code, "name": _rule_name(title), "shortDescription": {"text": title},
        "fullDescription": {"text": f"{title}; explained in {spec_anchor(code)} (`verify explain {code}`)"},
        "defaultConfiguration": {"level": LEVELS[CODES[code].severity]},
        "help": {"text": section, "markdown": section}}
    if docs:
        rule["helpUri"] = docs.rstrip("/") + "/" + spec_anchor(code)
    return rule


def _fingerprint(d: Diagnostic, sources: Mapping[str, SourceFile], seen: dict[str, int]) -> str:
    """A hash of the code, the file and the primary line's text (blanks collapsed), with ``:n`` counting
    equal ones: it does not change when lines are added or removed elsewhere in the file."""
    span = d.primary.span
    source = sources.get(span.file)
    line = " ".join(source.line(span.line).split()) if source is not None and span.line >= 1 else d.message
    key = hashlib.sha256(f"{d.code}\0{_uri(span.file)}\0{line}".encode("utf-8", "surrogatepass")).hexdigest()[:32]
    seen[key] = seen.get(key, 0) + 1
    return f"{key}:{seen[key]}"


def to_sarif(diagnostics: list[Diagnostic] | tuple[Diagnostic, ...],
             sources: Mapping[str, SourceFile] | None = None) -> dict[str, Any]:
    _uri_from.cache_clear()  # (files may have come or gone since the last log: each log looks afresh)
    codes = sorted({d.code for d in diagnostics})
    docs = documentation_uri()
    rules = [_rule(c, docs) for c in codes]
    index = {c: i for i, c in enumerate(codes)}
    results = []
    seen: dict[str, int] = {}
    for d in diagnostics:
        text = shown(d.message)
        if d.primary.message:
            text += f" ({shown(d.primary.message)})"
        extra = [f"note: {shown(n)}" for n in d.notes] + ([f"help: {shown(d.help)}"] if d.help else [])
        if extra:
            text += "\n" + "\n".join(extra)
        result = {"ruleId": d.code, "ruleIndex": index[d.code], "level": LEVELS[d.severity],
                  "message": {"text": text}, "locations": [_location(d.primary.span)],
                  "partialFingerprints": {"verifyFingerprint/v1": _fingerprint(d, sources or {}, seen)}}
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
