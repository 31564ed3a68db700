"""Colour for diagnostics on a terminal (rustc's palette): added to the rendered text, never part of it.

``paint`` adds ANSI escapes to text that ``verify.outputs.rendering.render_all_text`` made — severity and code,
the ``-->`` locations, the gutter, the carets under the source, ``help`` and ``note`` — and removing
them gives the text back unchanged. ``wanted(stream)`` says whether a stream gets colour: by default
(``--color auto``) only a terminal, never a pipe or a file, and never when ``NO_COLOR`` is set to
anything (no-color.org) or ``TERM`` is ``dumb``; ``--color always`` colours wherever the text goes (a
command-line choice overrides ``NO_COLOR``, as no-color.org has it), ``--color never`` nowhere
(``choose``).
"""
from __future__ import annotations

import os
import re
from typing import TextIO

RESET = "\x1b[0m"
BOLD = "\x1b[1m"
RED = "\x1b[1;31m"
YELLOW = "\x1b[1;33m"
BLUE = "\x1b[1;34m"
CYAN = "\x1b[1;36m"
_SEVERITY = {"error": RED, "warning": YELLOW, "note": CYAN}

_HEAD = re.compile(r"^(error|warning|note)(\[[A-Z]\d+\])?(:)(.*)$")
_WHERE = re.compile(r"^( *)(-->|:::)( .*)$")
_UNDERLINE = re.compile(r"^( *\|)( *)(\^+|-+)(.*)$")
_SOURCE = re.compile(r"^( *\d+ \|)(.*)$")
_BAR = re.compile(r"^( *\|)$")
_EXTRA = re.compile(r"^( *= )(help|note)(:.*)$")
_SUMMARY = re.compile(r"^(\d+ errors?)(, \d+ warnings?)?$|^(\d+ warnings?)$")
ANSI = re.compile(r"\x1b\[[0-9;]*m")

#: the choices of ``--color``
CHOICES = ("auto", "always", "never")
_choice = ["auto"]


def choose(choice: str) -> None:
    """Set ``--color``: "auto" (a terminal, unless NO_COLOR or TERM=dumb), "always" or "never"."""
    if choice not in CHOICES:
        raise ValueError(f"--color takes {', '.join(CHOICES)}, not {choice!r}")
    _choice[0] = choice


def wanted(stream: TextIO) -> bool:
    """Whether text written to ``stream`` should be coloured."""
    if _choice[0] != "auto":
        return _choice[0] == "always"
    if os.environ.get("NO_COLOR") or os.environ.get("TERM") == "dumb":
        return False
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


def paint(text: str) -> str:
    """``text`` (rendered diagnostics) with colour added, line by line."""
    return "\n".join(_paint_line(line) for line in text.split("\n"))


def _paint_line(line: str) -> str:
    if m := _HEAD.match(line):
        colour = _SEVERITY[m.group(1)]
        return f"{colour}{m.group(1)}{m.group(2) or ''}{RESET}{BOLD}{m.group(3)}{m.group(4)}{RESET}"
    if m := _WHERE.match(line):
        return f"{m.group(1)}{BLUE}{m.group(2)}{RESET}{m.group(3)}"
    if m := _UNDERLINE.match(line):
        colour = RED if m.group(3)[0] == "^" else BLUE
        return f"{BLUE}{m.group(1)}{RESET}{m.group(2)}{colour}{m.group(3)}{m.group(4)}{RESET}"
    if m := _SOURCE.match(line):
        return f"{BLUE}{m.group(1)}{RESET}{m.group(2)}"
    if m := _BAR.match(line):
        return f"{BLUE}{m.group(1)}{RESET}"
    if m := _EXTRA.match(line):
        return f"{BLUE}{m.group(1)}{RESET}{BOLD}{m.group(2)}{RESET}{m.group(3)}"
    if _SUMMARY.match(line):
        colour = RED if "error" in line else YELLOW
        return f"{colour}{line}{RESET}"
    return line
