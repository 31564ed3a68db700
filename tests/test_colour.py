"""Colour on a terminal only: never in a pipe or a file, never with NO_COLOR; colour is added to the
text, and removing it gives the plain text back."""
from __future__ import annotations

import io
import subprocess
import sys

from verify.cli import main
from verify.outputs.colour import ANSI, paint, wanted

BROKEN = "component Laser {\n  task LaserTask {\n    wcet 2 mss\n    wcet 3 ms\n  }\n}\n"


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _check(monkeypatch, tmp_path, stream: io.StringIO) -> str:
    path = tmp_path / "broken.vfy"
    path.write_text(BROKEN)
    monkeypatch.setattr(sys, "stderr", stream)
    assert main(["check", str(path)]) == 2
    return stream.getvalue()


def test_a_terminal_gets_colour_that_adds_nothing_but_escapes(monkeypatch, tmp_path):
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setenv("TERM", "xterm-256color")
    coloured = _check(monkeypatch, tmp_path, _Terminal())
    plain = _check(monkeypatch, tmp_path, io.StringIO())
    assert "\x1b[1;31merror[E001]\x1b[0m" in coloured and "\x1b[1;31m^^^" in coloured
    assert "\x1b[" not in plain
    assert ANSI.sub("", coloured) == plain


def test_no_color_and_dumb_terminals_get_none(monkeypatch, tmp_path):
    monkeypatch.setenv("NO_COLOR", "1")
    assert "\x1b[" not in _check(monkeypatch, tmp_path, _Terminal())
    monkeypatch.delenv("NO_COLOR")
    monkeypatch.setenv("TERM", "dumb")
    assert not wanted(_Terminal())


def test_a_pipe_gets_none(tmp_path):
    """The command's standard error is a pipe here: plain text, whatever TERM says."""
    path = tmp_path / "broken.vfy"
    path.write_text(BROKEN)
    run = "import sys; from verify.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.run([sys.executable, "-c", run, "check", str(path)], capture_output=True, text=True,
                          env={"TERM": "xterm-256color", "PATH": ""}, check=False)
    assert proc.returncode == 2 and "error[E001]: unknown unit `mss`" in proc.stderr
    assert "\x1b[" not in proc.stdout + proc.stderr


def test_paint_is_additive_on_every_line_shape():
    text = ("error[E101]: unknown name `x`\n --> a.vfy:3:5\n  |\n3 |   x\n  |   ^ here\n  |   - there\n"
            "  = note: n\n  = help: h\n\n2 errors, 1 warning\nwarning[E502]: w\nnote: plain")
    assert ANSI.sub("", paint(text)) == text
