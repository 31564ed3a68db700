"""Source files and spans: where in the user's text a node or a diagnostic lives."""
from __future__ import annotations

from dataclasses import dataclass


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

    def to(self, other: "Span") -> "Span":
        """The span from the start of ``self`` to the end of ``other``."""
        return Span(self.file, self.line, self.column, other.end_line, other.end_column)


NO_SPAN = Span("<none>", 0, 0, 0, 0)

#: the most characters of one source line that a snippet shows (``excerpt``)
SNIPPET_WIDTH = 100
ELLIPSIS = "…"


@dataclass(frozen=True)
class SourceFile:
    """The text of one file as read, for snippets in rendered diagnostics.

    ``only``, when set, is the one region of the file whose text may be shown: a file that is not text
    of the language from its first token (a file that is not a model at all: ``/etc/passwd``) is
    reported without showing anything of it but the offending token (README, "Running on untrusted
    input")."""

    path: str
    text: str
    only: Span | None = None

    def line(self, number: int) -> str:
        text = self.text[1:] if self.text.startswith("\ufeff") else self.text  # (parse skips a BOM)
        # lines as the lexer counts them: only "\n" ends one (``splitlines`` would also split at a form
        # feed, U+2028 and the like, and show the wrong line under a diagnostic)
        lines = text.split("\n")
        if not 1 <= number <= len(lines):
            return ""
        line = lines[number - 1].removesuffix("\r")
        if self.only is None:
            return line
        if number != self.only.line:
            return ""
        start = self.only.column - 1
        end = self.only.end_column - 1 if self.only.end_line == number else len(line)
        return " " * start + line[start:end]


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
