"""Source files and spans: where in the user's text a node or a diagnostic lives.

A :class:`Span` counts lines and columns as the lexer does: 1-based, a line ends at "\\n" only, a column is
a character (a code point) and a byte order mark before line 1 is not counted. A file's
:class:`SourceMap` (``SourceFile.map``) converts them to character offsets into the file's text and to
the positions of the Language Server Protocol (0-based lines, UTF-16 code units).
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass
from functools import cached_property


@dataclass(frozen=True, order=True)
class Span:
    """A region of one file. Lines and columns are 1-based; ``end_column`` is exclusive."""

    file: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"

    def to(self, other: Span) -> Span:
        """The span from the start of ``self`` to the end of ``other``."""
        return Span(self.file, self.line, self.column, other.end_line, other.end_column)


NO_SPAN = Span("<none>", 0, 0, 0, 0)

#: the most characters of one source line that a snippet shows (``excerpt``)
SNIPPET_WIDTH = 100
#: characters per block of a ``SourceMap``'s line index
INDEX_BLOCK = 256
ELLIPSIS = "…"


@dataclass(frozen=True)
class SourceFile:
    """The text of one file as read, for snippets in rendered diagnostics.

    ``only``, when set, is the one region of the file whose text may be shown: a file that is not text
    of the language from its first token (a file that is not a model at all: ``/etc/passwd``) is
    reported without showing anything of it but the offending token (docs/guide/untrusted.md,
    "What is confined")."""

    path: str
    text: str
    only: Span | None = None

    def line(self, number: int) -> str:
        """Line ``number`` (1-based) without its line end, "" past the text. Lines are those the lexer
        counts: only "\n" ends one (``splitlines`` would also split at a form feed, U+2028 and the like,
        and show the wrong line under a diagnostic); a byte order mark is not part of line 1. The line
        index (``map``) is built once per file, so a snippet costs the length of its line, not of the
        file."""
        index = self.map
        if not 1 <= number <= index.lines:
            return ""
        line = index.line_text(number).removesuffix("\r")
        if self.only is None:
            return line
        if number != self.only.line:
            return ""
        start = self.only.column - 1
        end = self.only.end_column - 1 if self.only.end_line == number else len(line)
        return " " * start + line[start:end]

    @cached_property
    def map(self) -> SourceMap:
        """Offsets and LSP positions of this file's spans."""
        return SourceMap(self.text)


class SourceMap:
    """Positions in one text: spans' (line, column) ↔ character offsets ↔ LSP positions.

    Offsets index the text as given (a byte order mark at its start included: line 1, column 1 is then
    offset 1). LSP positions are (line, character) with 0-based lines and characters counted in UTF-16
    code units, the byte order mark not counted, as an editor shows the text."""

    def __init__(self, text: str):
        self.text = text
        self.bom = 1 if text.startswith("\ufeff") else 0
        # the line index: the newlines before each block of ``INDEX_BLOCK`` characters (from the byte
        # order mark on), counted at C speed; a line's start is found from its block in at most
        # ``INDEX_BLOCK`` steps, so building it and each look-up stay linear however many lines a file has
        count, before, total = text.count, [0], 0
        for block in range(self.bom, len(text), INDEX_BLOCK):
            total += count("\n", block, block + INDEX_BLOCK)
            before.append(total)
        self._newlines_before = before
        self._lines = total + 1

    @property
    def lines(self) -> int:
        return self._lines

    def line_start(self, line: int) -> int:
        """The offset of the first character of ``line`` (1-based, clamped to the text's lines)."""
        newline = min(max(line, 1), self._lines) - 2  # (0-based: the "\n" that ends the line before)
        if newline < 0:
            return self.bom
        block = bisect.bisect_right(self._newlines_before, newline) - 1
        at = self.bom + block * INDEX_BLOCK - 1
        find = self.text.find
        for _ in range(newline - self._newlines_before[block] + 1):
            at = find("\n", at + 1)
        return at + 1

    def line_text(self, line: int) -> str:
        """The text of ``line`` (1-based, within the text) up to its "\\n"."""
        start = self.line_start(line)
        return self.text[start:self._end_of_line(start)]

    def _end_of_line(self, start: int) -> int:
        """The offset of the "\\n" ending the line that starts at ``start``, or of the end of the text."""
        end = self.text.find("\n", start)
        return end if end >= 0 else len(self.text)

    def offset(self, line: int, column: int) -> int:
        """The offset of (``line``, ``column``), both 1-based; clamped to the text (a column past the end
        of its line is the line's end)."""
        start = self.line_start(line)
        return min(start + max(column, 1) - 1, self._end_of_line(start))

    def span_offsets(self, span: Span) -> tuple[int, int]:
        """The offsets of ``span``'s start and (exclusive) end."""
        return self.offset(span.line, span.column), self.offset(span.end_line, span.end_column)

    def position(self, offset: int) -> tuple[int, int]:
        """The 1-based (line, column) of ``offset``."""
        offset = min(max(offset, self.bom), len(self.text))
        block = (offset - self.bom) // INDEX_BLOCK
        line = self._newlines_before[block] + self.text.count("\n", self.bom + block * INDEX_BLOCK, offset) + 1
        start = max(self.text.rfind("\n", 0, offset) + 1, self.bom)
        return line, offset - start + 1

    def to_lsp(self, line: int, column: int) -> tuple[int, int]:
        """The LSP position (0-based line, UTF-16 character) of 1-based (``line``, ``column``)."""
        start = self.line_start(line)
        before = self.text[start:self.offset(line, column)]
        return min(max(line, 1), self._lines) - 1, len(before) + sum(1 for ch in before if ord(ch) > 0xFFFF)

    def from_lsp(self, line: int, character: int) -> tuple[int, int]:
        """The 1-based (line, column) of an LSP position (a character inside a surrogate pair, or past the
        end of the line, is moved to the next whole character or the line's end)."""
        index = min(max(line, 0), self._lines - 1)
        start = self.line_start(index + 1)
        end = self._end_of_line(start)
        units = column = 0
        while units < character and start + column < end:
            units += 2 if ord(self.text[start + column]) > 0xFFFF else 1
            column += 1
        return index + 1, column + 1

    def lsp_range(self, span: Span) -> dict[str, dict[str, int]]:
        """``span`` as an LSP ``Range``."""
        (sl, sc), (el, ec) = self.to_lsp(span.line, span.column), self.to_lsp(span.end_line, span.end_column)
        return {"start": {"line": sl, "character": sc}, "end": {"line": el, "character": ec}}


def excerpt(line: str, start: int, end: int, width: int = SNIPPET_WIDTH) -> tuple[str, int, int]:
    """At most ``width`` characters of ``line`` around columns [``start``, ``end``) (1-based), each cut end
    marked with an ellipsis: (the text, and the columns of the region in it). Every renderer that shows
    source text shows it through this function, so no snippet echoes more of a line than this."""
    if len(line) <= width:
        return line, start, end
    start = min(max(start, 1), len(line) + 1)
    first = max(0, min(start - 1 - width // 4, len(line) - width))  # a quarter of the width before
    last = first + width
    shown = line[first:last]
    shift = first
    if first > 0:
        shown = ELLIPSIS + shown
        shift -= 1
    if last < len(line):
        shown += ELLIPSIS
    new_start = start - shift
    new_end = max(new_start + 1, min(end - shift, len(shown) + 1 - (last < len(line))))
    return shown, new_start, new_end
