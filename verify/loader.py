"""Read a project: the root file and everything it imports, each file once, cycles reported.

Files are read as bytes and decoded as strict UTF-8; unreadable, missing or non-UTF-8 files become
located diagnostics (E003, E004), never exceptions. Imports are resolved relative to the importing file.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field

from . import syntax as s
from .diagnostics import DiagnosticSink
from .parse import parse_text
from .source import Span, SourceFile

MAX_FILE_BYTES = 16 * 1024 * 1024


@dataclass(frozen=True)
class Project:
    """The parsed files of one project, root first, then imports in the order they were reached."""

    root: str
    modules: tuple[s.Module, ...]
    sources: dict[str, SourceFile] = field(compare=False, repr=False)

    @property
    def root_module(self) -> s.Module | None:
        return next((m for m in self.modules if m.path == self.root), None)

    @property
    def components(self) -> tuple[s.Component, ...]:
        return tuple(c for m in self.modules for c in m.components)

    @property
    def systems(self) -> tuple[s.System, ...]:
        return tuple(sy for m in self.modules for sy in m.systems)


def _read(path: str, sink: DiagnosticSink, at: Span | None,
          sources: dict[str, SourceFile] | None = None) -> str | None:
    """The text of ``path``, or None after reporting why not. A file that is not UTF-8 is still put in
    ``sources`` (undecodable bytes replaced) so that the report can show the offending line."""
    where = at or Span(path, 1, 1, 1, 1)
    shown = _shown(path)
    try:
        # a FIFO, a device or a socket would block or never end: only regular files are read, checked
        # before opening and again on the open descriptor (opened non-blocking, so a FIFO swapped in
        # between cannot hang the read either)
        if not stat.S_ISREG(os.stat(path).st_mode):
            _not_regular(shown, path, where, sink)
            return None
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
        with os.fdopen(fd, "rb") as fh:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                _not_regular(shown, path, where, sink)
                return None
            data = fh.read(MAX_FILE_BYTES + 1)
    except ValueError:  # e.g. a NUL character in the path: no file can have that name
        sink.emit("E004", f"invalid file name {shown}: it contains a NUL character", where, "cannot be read",
                  help="correct the file name")
        return None
    except FileNotFoundError:
        sink.emit("E004", f"file not found: {shown}", where, "cannot be read",
                  help="check the path; imports are relative to the importing file")
        return None
    except IsADirectoryError:
        sink.emit("E004", f"{shown} is a directory, not a file", where, "cannot be read",
                  help="name a .vfy file")
        return None
    except OSError as err:
        sink.emit("E004", f"cannot read {shown}: {err.strerror or err}", where, "cannot be read",
                  help="check that the file exists and is readable")
        return None
    if len(data) > MAX_FILE_BYTES:
        sink.emit("E004", f"{path} is larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB", where,
                  "too large", help="split the model into several files joined by `import`")
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        before = data[: err.start]
        line = before.count(b"\n") + 1
        col = len(before[before.rfind(b"\n") + 1:].decode("utf-8")) + 1  # in characters, as in the snippet
        if sources is not None:
            sources[path] = SourceFile(path, data.decode("utf-8", errors="replace"))
        sink.emit("E003", f"{path} is not UTF-8 text: byte 0x{data[err.start]:02x} at offset {err.start}",
                  Span(path, line, col, line, col + 1), "not UTF-8",
                  help="save the file as UTF-8 (it may have been saved as Latin-1 or Windows-1252)")
        return None


def _shown(path: str) -> str:
    """``path`` for a message: characters that cannot be shown (NUL, control characters) escaped."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in path)


def _not_regular(shown: str, path: str, where: Span, sink: DiagnosticSink) -> None:
    if os.path.isdir(path):
        sink.emit("E004", f"{shown} is a directory, not a file", where, "cannot be read", help="name a .vfy file")
        return
    sink.emit("E004", f"{shown} is not a regular file (a pipe, device or socket)", where, "cannot be read",
              help="name a regular .vfy file; to check generated text, write it to a file first")


def load_project(root: str, sink: DiagnosticSink) -> Project:
    """Parse ``root`` and its imports. Diagnostics go to ``sink``; the project holds what parsed."""
    if not root:
        sink.emit("E004", "no file name given", Span("<command line>", 1, 1, 1, 1), "cannot be read",
                  help="name a .vfy file, e.g. `verify check examples/navigation/navigation.vfy`")
        return Project(root, (), {})
    root = os.path.normpath(root)
    modules: list[s.Module] = []
    sources: dict[str, SourceFile] = {}
    seen: dict[str, str] = {}  # realpath -> display path
    stack: list[str] = []  # realpaths on the current import path

    def visit(path: str, at: Span | None) -> None:
        try:
            real = os.path.realpath(path)
        except ValueError:  # a NUL character in the path: ``_read`` reports it
            _read(path, sink, at, sources)
            return
        if real in stack:
            cycle = [seen[r] for r in stack[stack.index(real):]] + [seen[real]]
            sink.emit("E103", "import cycle: " + " -> ".join(cycle), at or Span(path, 1, 1, 1, 1),
                      "closes the cycle", help="move what both files need into a third file that both import")
            return
        if real in seen:
            return
        seen[real] = path
        text = _read(path, sink, at, sources)
        if text is None:
            return
        sources[path] = SourceFile(path, text)
        module = parse_text(text, path, sink)
        if module is None:
            return
        modules.append(module)
        stack.append(real)
        base = os.path.dirname(path)
        for imp in module.imports:
            target = os.path.normpath(os.path.join(base, imp.path))
            visit(target, imp.span)
        stack.pop()

    visit(root, None)
    del visit  # (a closure that refers to itself: left alone, the cycle would keep every module alive until the
    # next full collection, which ``gcpause`` defers)
    return Project(root, tuple(modules), sources)


def project_from_text(text: str, path: str, sink: DiagnosticSink) -> Project:
    """A one-file project from text in memory (imports are not followed)."""
    module = parse_text(text, path, sink)
    if module is not None:
        for imp in module.imports:
            sink.emit("E004", f"imports are not followed for in-memory text: {imp.path}", imp.span,
                      "not followed", help="load the file from disk instead")
    return Project(path, (module,) if module else (), {path: SourceFile(path, text)})
