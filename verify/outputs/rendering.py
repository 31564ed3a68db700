"""Renderers for diagnostics: rustc-style text with source snippets, and JSON (schema below).

JSON schema ``verify.diagnostics/1``::

    {"schema": "verify.diagnostics/1",
     "diagnostics": [{"code", "severity", "message", "file", "line", "column", "end_line",
                      "end_column", "label", "secondary": [{"file", "line", "column", "end_line",
                      "end_column", "message"}], "notes": [...], "help": str | null, "spec": str}],
     "summary": {"errors": int, "warnings": int}}

Lines and columns are 1-based; ``end_column`` is exclusive; 0 for a diagnostic about a whole file (one
named on the command line that cannot be read) or about no file. A snippet of source text shows at most
``source.SNIPPET_WIDTH`` characters of a line (``source.excerpt``), and nothing of a file that is not a
model but its offending token (``SourceFile.only``). In text, every field (file names, message, labels,
notes, help) and every snippet is shown through ``verify.core.sanitize``: a character that is not printable
(ESC, BEL, CR, a newline in a name from another tool's file) appears as its escape (``\\x1b``), never
raw; JSON escapes them itself.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ..core.codes import spec_anchor
from ..core.diagnostics import Diagnostic, Label, Severity
from ..core.sanitize import shown, shown_columns
from ..core.source import ELLIPSIS, SourceFile, Span, excerpt

#: the most diagnostics of one file that the text rendering shows; the rest are counted in one line
#: ("… and N more errors in FILE"; JSON and SARIF list every one)
TEXT_PER_FILE = 100


def _gutter_width(d: Diagnostic) -> int:
    lines = [d.primary.span.line] + [lb.span.line for lb in d.secondary]
    return max(len(str(n)) for n in lines)


def _snippet(label: Label, marker: str, sources: Mapping[str, SourceFile], width: int) -> list[str]:
    span = label.span
    source = sources.get(span.file)
    if source is None or span.line < 1:
        return []
    text = source.line(span.line).replace("\t", " ")
    start = max(span.column, 1)
    end = span.end_column if span.end_line == span.line else len(text) + 1
    text, start, end = shown_columns(*excerpt(text, start, end))
    length = max(1, min(end, len(text) + 1) - start)
    pad = " " * width
    underline = " " * (start - 1) + marker * length
    if label.message:
        underline += " " + shown(label.message)
    return [f"{str(span.line).rjust(width)} | {text}", f"{pad} | {underline}"]


def render_text(d: Diagnostic, sources: Mapping[str, SourceFile]) -> str:
    """One diagnostic, rustc-style."""
    width = _gutter_width(d)
    pad = " " * width
    out = [f"{d.severity.value}[{d.code}]: {shown(d.message)}", f"{pad}--> {_where(d.primary.span)}"]
    snippet = _snippet(d.primary, "^", sources, width)
    if snippet:
        out.append(f"{pad} |")
        out.extend(snippet)
    for label in d.secondary:
        if label.span.file != d.primary.span.file:
            out.append(f"{pad}::: {_where(label.span)}")
        lines = _snippet(label, "-", sources, width)
        if lines:
            out.append(f"{pad} |")
            out.extend(lines)
    if snippet or d.secondary:
        out.append(f"{pad} |")
    for note in d.notes:
        out.append(f"{pad} = note: {shown(note)}")
    if d.help:
        out.append(f"{pad} = help: {shown(d.help)}")
    return "\n".join(out)


def _where(span: Span) -> str:
    return f"{shown(span.file)}:{span.line}:{span.column}" if span.line > 0 else shown(span.file)


def summary_line(diagnostics: Sequence[Diagnostic]) -> str:
    errors = sum(1 for d in diagnostics if d.severity is Severity.ERROR)
    warnings = sum(1 for d in diagnostics if d.severity is Severity.WARNING)
    parts = []
    if errors:
        parts.append(f"{errors} error{'s' if errors != 1 else ''}")
    if warnings:
        parts.append(f"{warnings} warning{'s' if warnings != 1 else ''}")
    return ", ".join(parts)


def render_all_text(diagnostics: Sequence[Diagnostic], sources: Mapping[str, SourceFile],
                    per_file: int = TEXT_PER_FILE) -> str:
    """Every diagnostic rustc-style, at most ``per_file`` of each file (that of its primary span, in the
    order given); then, for each file with more, "… and N more errors in FILE"; then the summary line,
    which counts them all."""
    counted: dict[str, int] = {}
    held: dict[str, list[Diagnostic]] = {}
    blocks = []
    for d in diagnostics:
        file = d.primary.span.file
        if counted.get(file, 0) < per_file:
            counted[file] = counted.get(file, 0) + 1
            blocks.append(render_text(d, sources))
        else:
            held.setdefault(file, []).append(d)
    blocks.extend(f"{ELLIPSIS} and {_more(rest)} in {shown(file)}" for file, rest in held.items())
    if blocks:
        blocks.append(summary_line(diagnostics))
    return "\n\n".join(blocks)


def _more(diagnostics: Sequence[Diagnostic]) -> str:
    """"5 more errors", "1 more error and 2 more warnings" ... (the severities among ``diagnostics``)."""
    counts = [(severity.value, sum(1 for d in diagnostics if d.severity is severity)) for severity in Severity]
    return " and ".join(f"{n} more {word}{'s' if n != 1 else ''}" for word, n in counts if n)


def _span_json(span: Span) -> dict[str, str | int]:
    return {"file": span.file, "line": span.line, "column": span.column,
            "end_line": span.end_line, "end_column": span.end_column}


def diagnostic_json(d: Diagnostic) -> dict[str, Any]:
    return {
        "code": d.code,
        "severity": d.severity.value,
        "message": d.message,
        **_span_json(d.primary.span),
        "label": d.primary.message,
        "secondary": [{**_span_json(lb.span), "message": lb.message} for lb in d.secondary],
        "notes": list(d.notes),
        "help": d.help,
        "spec": spec_anchor(d.code),
    }


def diagnostics_json(diagnostics: Sequence[Diagnostic]) -> dict[str, Any]:
    return {
        "schema": "verify.diagnostics/1",
        "diagnostics": [diagnostic_json(d) for d in diagnostics],
        "summary": {
            "errors": sum(1 for d in diagnostics if d.severity is Severity.ERROR),
            "warnings": sum(1 for d in diagnostics if d.severity is Severity.WARNING),
        },
    }
