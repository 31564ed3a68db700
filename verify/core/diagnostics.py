"""Diagnostics as values: code, severity, message, primary and secondary labels, notes, help.

Renderers (``verify.outputs.rendering``) turn them into text, JSON or SARIF; nothing here prints. Every code is
registered in ``verify.core.codes`` with its title and the section of ``specs/diagnostics.md`` that shows a
minimal failing example.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from itertools import islice

from .codes import CODES
from .severity import Severity as Severity
from .source import NO_SPAN, Span


@dataclass(frozen=True)
class Label:
    span: Span
    message: str = ""


@dataclass(frozen=True)
class Diagnostic:
    code: str
    severity: Severity
    message: str
    primary: Label
    secondary: tuple[Label, ...] = ()
    notes: tuple[str, ...] = ()
    help: str | None = None

    @property
    def span(self) -> Span:
        return self.primary.span

    def sort_key(self) -> tuple[str, int, int, str, str]:
        s = self.primary.span
        return (s.file, s.line, s.column, self.code, self.message)


@dataclass
class DiagnosticSink:
    """Collects diagnostics from a pass; passes never stop at the first error."""

    items: list[Diagnostic] = field(default_factory=list)

    def add(self, diagnostic: Diagnostic) -> None:
        self.items.append(diagnostic)

    def emit(
        self,
        code: str,
        message: str,
        span: Span = NO_SPAN,
        label: str = "",
        *,
        secondary: tuple[Label, ...] | list[Label] = (),
        notes: tuple[str, ...] | list[str] = (),
        help: str | None = None,
        severity: Severity | None = None,
    ) -> Diagnostic:
        severity = severity or CODES[code].severity
        d = Diagnostic(code, severity, message, Label(span, label), tuple(secondary), tuple(notes), help)
        self.items.append(d)
        return d

    @property
    def has_errors(self) -> bool:
        return any(d.severity is Severity.ERROR for d in self.items)


def has_errors(diagnostics: list[Diagnostic] | tuple[Diagnostic, ...]) -> bool:
    return any(d.severity is Severity.ERROR for d in diagnostics)


def suggest(word: str, candidates: Iterable[str]) -> str | None:
    """The closest candidate for a misspelt name ("did you mean ...?"), or None."""
    import difflib

    pool = sorted(set(candidates))
    matches = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
    if not matches:
        lowered = {c.lower(): c for c in pool}
        if word.lower() in lowered:
            return lowered[word.lower()]
        return None
    return matches[0]


def name_list(names: Iterable[str], limit: int = 12) -> str:
    """Names for a message, each in backquotes: at most ``limit`` of them, then how many more (a
    diagnostic about a task on a crowded core stays readable; of a sequence, only the names shown are
    visited)."""
    seq = names if isinstance(names, Sequence) else list(names)
    shown = ", ".join(f"`{n}`" for n in islice(seq, limit))
    return shown + (f" and {len(seq) - limit} more" if len(seq) > limit else "")
