"""A tolerant reader for the textual syntax of Xtext languages (SmartMDSD's models are written in them).

Tokens: identifiers (an Xtext ``^`` escape is dropped), numbers (``10``, ``37.5``, ``.5``, ``1e-3``),
strings, punctuation, and comments (``//``, ``/* */``, ``/** */`` documentation), with their spans.
``Cursor`` walks the tokens for a small recursive-descent reader of one file kind: ``expect`` reports an
unexpected token as E701 (``Stop`` ends the file), and ``skip_element`` steps over an element the
reader does not know, so that it can be reported (E703) instead of ending the file.
"""
from __future__ import annotations

import re
from collections.abc import Collection
from dataclasses import dataclass
from fractions import Fraction

from ..core.diagnostics import DiagnosticSink
from ..core.limits import DEFAULT_LIMITS
from ..core.sanitize import shown
from ..core.source import Span

_TOKEN = re.compile(r"""
    (?P<ws>[ \t\r\n\f\ufeff]+)
  | (?P<comment>//[^\n]*|/\*.*?\*/)
  | (?P<num>[0-9]+(?:\.[0-9]+)?(?:[eE]-?[0-9]+)?|\.[0-9]+(?:[eE]-?[0-9]+)?)
  | (?P<id>\^?[A-Za-z_][A-Za-z0-9_]*)
  | (?P<str>"(?:[^"\\\n]|\\.)*"|'(?:[^'\\\n]|\\.)*')
  | (?P<punct>->|\#import|[{}();=.,\-:\[\]<>*\#])
""", re.VERBOSE | re.DOTALL)

#: the most tokens one imported file may hold (as the language's own limit: verify.core.limits)
MAX_TOKENS = 2_000_000
#: the largest exponent of a number (``1e-3``) in an imported file (10^40: far beyond any time or rate)
MAX_EXPONENT = 40


@dataclass(frozen=True)
class Tok:
    kind: str  # "id", "num", "str", "punct", "eof"
    text: str
    span: Span

    def __str__(self) -> str:
        return "the end of the file" if self.kind == "eof" else f"`{self.text}`"


class Stop(Exception):
    """The file cannot be read further (an E701 was reported)."""


def tokenize(text: str, path: str, sink: DiagnosticSink) -> list[Tok] | None:
    """The tokens of ``text`` (comments and white space dropped), or None after an E701 for a character
    that no token starts with, or an E008 when there are too many."""
    toks: list[Tok] = []
    line, line_start, pos = 1, 0, 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            col = pos - line_start + 1
            ch = text[pos]
            sink.emit("E701", f"unexpected character `{shown(ch)}` in {path}", Span(path, line, col, line, col + 1),
                      "not part of the format", help="the file must be a SmartMDSD model as its editor writes it")
            return None
        kind = m.lastgroup or ""
        value = m.group()
        if kind not in ("ws", "comment"):
            end = pos + len(value)
            span = Span(path, line, pos - line_start + 1, line, end - line_start + 1)
            toks.append(Tok(kind, value[1:] if kind == "id" and value.startswith("^") else value, span))
            if len(toks) > MAX_TOKENS:
                sink.emit("E008", f"{path} has more than {MAX_TOKENS:,} tokens, the limit for one file", span,
                          "too many tokens", help="import a smaller model")
                return None
        newlines = value.count("\n")
        if newlines:
            line += newlines
            line_start = pos + value.rindex("\n") + 1
        pos = m.end()
    toks.append(Tok("eof", "", Span(path, line, pos - line_start + 1, line, pos - line_start + 1)))
    return toks


class Cursor:
    def __init__(self, toks: list[Tok], path: str, sink: DiagnosticSink, what: str):
        self.toks, self.path, self.sink, self.what = toks, path, sink, what
        self.i = 0

    def peek(self, k: int = 0) -> Tok:
        return self.toks[min(self.i + k, len(self.toks) - 1)]

    def next(self) -> Tok:
        tok = self.peek()
        if tok.kind != "eof":
            self.i += 1
        return tok

    def at(self, *texts: str) -> bool:
        tok = self.peek()
        return tok.kind in ("id", "punct") and tok.text in texts

    def accept(self, text: str) -> Tok | None:
        return self.next() if self.at(text) else None

    def semi(self) -> None:
        """An optional ``;`` (Xtext's ``(';')?``)."""
        self.accept(";")

    def fail(self, tok: Tok, expected: str) -> Stop:
        self.sink.emit("E701", f"unexpected {tok} in {self.what}: expected {expected}", tok.span,
                       f"expected {expected}",
                       help="the file must be a SmartMDSD model as its editor writes it (see specs/interop.md)")
        return Stop()

    def expect(self, text: str) -> Tok:
        if not self.at(text):
            raise self.fail(self.peek(), f"`{text}`")
        return self.next()

    def ident(self, what: str = "a name") -> Tok:
        tok = self.peek()
        if tok.kind != "id":
            raise self.fail(tok, what)
        return self.next()

    def fqn(self, what: str = "a name") -> Tok:
        """A qualified name ``A.B.C`` as one token (its span covering all parts)."""
        first = self.ident(what)
        parts, span = [first.text], first.span
        while self.at(".") and self.peek(1).kind == "id":
            self.next()
            last = self.next()
            parts.append(last.text)
            span = span.to(last.span)
        return Tok("id", ".".join(parts), span)

    def integer(self, what: str = "an integer") -> tuple[int, Span]:
        neg = self.accept("-")
        tok = self.peek()
        if tok.kind != "num" or not tok.text.isdigit():
            raise self.fail(tok, what)
        self.bounded(tok)
        self.next()
        value = int(tok.text)
        return (-value if neg else value), (neg.span.to(tok.span) if neg else tok.span)

    def decimal(self, what: str = "a number") -> tuple[Fraction, Span]:
        """An Xtext ``EDouble`` (``10.0``, ``37.5``), exactly."""
        neg = self.accept("-")
        tok = self.peek()
        if tok.kind != "num":
            raise self.fail(tok, what)
        self.bounded(tok)
        self.next()
        mantissa, _, exponent = tok.text.lower().partition("e")
        if abs(int(exponent or "0")) > MAX_EXPONENT:
            raise self.out_of_range(tok, f"its exponent is larger than {MAX_EXPONENT}", "write the value in a "
                                    "larger or smaller unit")
        value = Fraction(mantissa) * (Fraction(10) ** int(exponent or "0"))
        return (-value if neg else value), (neg.span.to(tok.span) if neg else tok.span)

    def bounded(self, tok: Tok) -> None:
        """E005 (and ``Stop``) for a number of more than ``number_length`` characters, the language's own
        limit (``verify.core.limits``): no number is ever converted whole if it is longer."""
        if len(tok.text) > DEFAULT_LIMITS.number_length:
            raise self.out_of_range(tok, f"it has {len(tok.text):,} characters; at most "
                                    f"{DEFAULT_LIMITS.number_length} are allowed", "write a shorter number")

    def out_of_range(self, tok: Tok, why: str, help: str) -> Stop:
        self.sink.emit("E005", f"invalid number in {self.what}: {why}", tok.span, "out of range", help=help)
        return Stop()

    def block(self) -> Span:
        """Skip a balanced ``{ … }`` (the cursor is at its ``{``); its span."""
        start = self.expect("{")
        depth, end = 1, start.span
        while depth:
            tok = self.next()
            if tok.kind == "eof":
                raise self.fail(tok, "`}`")
            end = tok.span
            if tok.kind == "punct" and tok.text == "{":
                depth += 1
            elif tok.kind == "punct" and tok.text == "}":
                depth -= 1
        return start.span.to(end)

    def skip_element(self, known: Collection[str]) -> tuple[Tok, Span]:
        """Step over an element the reader does not know: its first token and its span. It ends after a
        ``;``, after a balanced ``{ … }``, or before the ``}`` of the enclosing block or a keyword in
        ``known`` that starts the next element."""
        first = self.next()
        span = first.span
        if first.kind == "punct" and first.text == "{":
            self.i -= 1
            return first, self.block()
        while True:
            tok = self.peek()
            closing = tok.kind == "punct" and tok.text == "}"
            if tok.kind == "eof" or closing or (tok.kind == "id" and tok.text in known):
                return first, span
            if tok.kind == "punct" and tok.text == ";":
                self.next()
                return first, span.to(tok.span)
            if tok.kind == "punct" and tok.text == "{":
                return first, span.to(self.block())
            self.next()
            span = span.to(tok.span)
