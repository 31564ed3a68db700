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


@dataclass(frozen=True)
class SourceFile:
    """The text of one file as read, for snippets in rendered diagnostics."""

    path: str
    text: str

    def line(self, number: int) -> str:
        text = self.text[1:] if self.text.startswith("\ufeff") else self.text  # (parse skips a BOM)
        # lines as the lexer counts them: only "\n" ends one (``splitlines`` would also split at a form
        # feed, U+2028 and the like, and show the wrong line under a diagnostic)
        lines = text.split("\n")
        if 1 <= number <= len(lines):
            return lines[number - 1].removesuffix("\r")
        return ""
