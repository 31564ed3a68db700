"""Read a project: the root file and everything it imports, each file once, cycles reported.

Files are read as bytes and decoded as strict UTF-8; unreadable, missing or non-UTF-8 files become
located diagnostics (E003, E004), never exceptions. An import is confined to the project's allowed
directories before anything is opened (``verify.frontend.roots``: E006, E007), every file read — the root file
too — obeys the rule of ``verify.core.fileaccess`` (inside those directories once links are followed, a
regular file: E006, E004), and what one run reads is bounded (``verify.core.limits``: E008). Text held in
memory (an editor's unsaved buffers) takes the place of a file of the same path (``overlay``).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from collections.abc import Callable, Mapping
from typing import BinaryIO

from ..model import syntax as s
from ..core.diagnostics import DiagnosticSink
from ..core.fileaccess import Area, Refused, read_regular
from ..core.limits import DEFAULT_LIMITS, Limits
from .fastparse import looks_like_model
from .parse import parse_source
from .roots import Refusal, Roots
from ..core.source import Span, SourceFile


#: text held in memory in place of files (an editor's unsaved buffers): a mapping from paths, or a
#: function of an absolute path giving the text or None (then the file on disk is read)
Overlay = Mapping[str, str] | Callable[[str], str | None]


@dataclass(frozen=True)
class Project:
    """The parsed files of one project, root first, then imports in the order they were reached."""

    root: str
    modules: tuple[s.Module, ...]
    sources: dict[str, SourceFile] = field(compare=False, repr=False)
    #: for each file with a syntax error, what error recovery made of it (``parse.Parsed.partial``):
    #: not resolved or validated, for an editor's outline and completion
    partials: dict[str, s.Module] = field(default_factory=dict, compare=False, repr=False)

    @property
    def root_module(self) -> s.Module | None:
        return next((m for m in self.modules if m.path == self.root), None)

    @property
    def components(self) -> tuple[s.Component, ...]:
        return tuple(c for m in self.modules for c in m.components)

    @property
    def systems(self) -> tuple[s.System, ...]:
        return tuple(sy for m in self.modules for sy in m.systems)


def _shown(path: str) -> str:
    """``path`` for a message: characters that cannot be shown (NUL, control characters) escaped."""
    from ..core.sanitize import shown

    return shown(path)


def read_bytes(path: str, sink: DiagnosticSink, at: Span | None,
               limit: int = DEFAULT_LIMITS.file_bytes, area: Area | None = None) -> bytes | None:
    """The bytes of regular file ``path``, at most ``limit`` + 1 of them (more than ``limit``: the file is
    too large), or None after reporting why it cannot be read. Within ``area`` (when given) as written
    and once links are followed (``verify.core.fileaccess``: the one rule of every file read)."""
    where = at or Span(path, 0, 0, 0, 0)  # (a file named on the command line: no line to point at)
    shown = _shown(path)
    try:
        return read_regular(path, limit, area)
    except Refused as refused:
        _refused(refused.reason, shown, where, sink, imported=at is not None)
    except OSError as err:
        sink.emit("E004", f"cannot read {shown}: {err.strerror or err}", where, "cannot be read",
                  help="check that the file exists and is readable")
    return None


def _refused(reason: str, shown: str, where: Span, sink: DiagnosticSink, imported: bool = True) -> None:
    """The diagnostic of a file ``verify.core.fileaccess`` refuses: its name, never its content."""
    if reason in ("outside", "link"):
        sink.emit("E006", f"{shown} is a symbolic link to a file outside the allowed directories; it is not read",
                  where, "leads outside", help="copy the file into the project, or name the directory it lies in "
                  "on the command line")
    elif reason == "name":
        sink.emit("E004", f"invalid file name {shown}: it contains a NUL character", where, "cannot be read",
                  help="correct the file name")
    elif reason == "missing":
        sink.emit("E004", f"file not found: {shown}", where, "cannot be read",
                  help="check the path; imports are relative to the importing file" if imported else
                  f"check the path (relative to the working directory, {_shown(os.getcwd())})")
    elif reason == "directory":
        sink.emit("E004", f"{shown} is a directory, not a file", where, "cannot be read", help="name a .vfy file")
    else:
        sink.emit("E004", f"{shown} is not a regular file (a pipe, device or socket)", where, "cannot be read",
                  help="name a regular .vfy file; to check generated text, write it to a file first")


def read_stream(stream: BinaryIO, path: str, sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> str | None:
    """The text of ``stream`` (standard input: FILE ``-``), named ``path`` in messages, within the size
    limit of one file, or None after an E003 or E008 (the text read so far in ``sources`` is not kept)."""
    try:
        data = stream.read(limits.file_bytes + 1)
    except OSError as err:
        sink.emit("E004", f"cannot read {path}: {err.strerror or err}", Span(path, 1, 1, 1, 1), "cannot be read",
                  help="pipe a model into the command, or name a file")
        return None
    if len(data) > limits.file_bytes:
        _file_too_large(path, limits, None, sink)
        return None
    return decode(data, path, sink)


def _size(limit: int) -> str:
    mib = 1024 * 1024
    return f"{limit // mib} MiB" if limit % mib == 0 else f"{limit:,} bytes"


def decode(data: bytes, path: str, sink: DiagnosticSink, sources: dict[str, SourceFile] | None = None) -> str | None:
    """``data`` as strict UTF-8, or None after an E003. The file is still put in ``sources`` (undecodable
    bytes replaced) so that the report can show where; a file that does not look like a model shows
    nothing but the offending byte."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        before = data[: err.start]
        line = before.count(b"\n") + 1
        col = len(before[before.rfind(b"\n") + 1:].decode("utf-8")) + 1  # in characters, as in the snippet
        span = Span(path, line, col, line, col + 1)
        if sources is not None:
            text = data.decode("utf-8", errors="replace")
            prefix = before.decode("utf-8")
            model_like = looks_like_model(prefix) and prefix.strip() != ""  # (a bad first byte: not a model)
            sources[path] = SourceFile(path, text, None if model_like else span)
        sink.emit("E003", f"{_shown(path)} is not UTF-8 text: byte 0x{data[err.start]:02x} at offset {err.start}",
                  span, "not UTF-8", help="save the file as UTF-8 (it may have been saved as Latin-1 or Windows-1252)")
        return None


def _read(path: str, sink: DiagnosticSink, at: Span | None, sources: dict[str, SourceFile] | None = None,
          limits: Limits = DEFAULT_LIMITS, area: Area | None = None) -> str | None:
    """The text of one file ``path``, or None after reporting why not (E003, E004, E006, E008)."""
    data = read_bytes(path, sink, at, limits.file_bytes, area)
    if data is None:
        return None
    if len(data) > limits.file_bytes:
        _file_too_large(path, limits, at, sink)
        return None
    return decode(data, path, sink, sources)


def read_text(path: str, sink: DiagnosticSink, sources: dict[str, SourceFile] | None = None,
              limits: Limits = DEFAULT_LIMITS, area: Area | None = None) -> str | None:
    """The text of file ``path`` (any format: importers read theirs with it), or None after reporting why
    not (E003, E004, E006, E008), under the same guards as a model file (within ``area`` when given)."""
    return _read(path, sink, None, sources, limits, area)


def _file_too_large(path: str, limits: Limits, at: Span | None, sink: DiagnosticSink) -> None:
    sink.emit("E008", f"{_shown(path)} is larger than {_size(limits.file_bytes)}, the limit for one file",
              at or Span(path, 1, 1, 1, 1), "too large", help="split the model into several files joined by `import`")


class _Loading:
    """The state of one ``load_project``: what was read, the budget left, the import path."""

    def __init__(self, sink: DiagnosticSink, roots: Roots, limits: Limits, overlay: Overlay | None):
        self.sink = sink
        self.roots = roots
        self.limits = limits
        if callable(overlay):
            self.held: Callable[[str], str | None] = overlay
        else:
            self.held = {os.path.abspath(p): t for p, t in (overlay or {}).items()}.get
        self.modules: list[s.Module] = []
        self.sources: dict[str, SourceFile] = {}
        self.partials: dict[str, s.Module] = {}
        self.seen: dict[str, str] = {}  # realpath -> display path
        self.stack: list[str] = []  # realpaths on the current import path
        self.total = 0  # bytes read

    def text(self, path: str, at: Span | None) -> str | None:
        """The text of ``path``: an overlay's, else the file's (within the size limits)."""
        held = self.held(os.path.abspath(path))
        if held is not None:
            size = len(held.encode("utf-8", errors="surrogatepass"))
            if not self._fits(path, size, at):
                return None
            self.total += size
            return held
        data = read_bytes(path, self.sink, at, min(self.limits.file_bytes, self.limits.project_bytes - self.total),
                          self.roots.area)
        if data is None or not self._fits(path, len(data), at):
            return None
        self.total += len(data)
        return decode(data, path, self.sink, self.sources)

    def _fits(self, path: str, size: int, at: Span | None) -> bool:
        """``size`` more bytes from ``path`` are within the limits (else an E008)."""
        if size > self.limits.file_bytes:
            _file_too_large(path, self.limits, at, self.sink)
            return False
        if self.total + size > self.limits.project_bytes:
            self.sink.emit("E008", f"reading {_shown(path)} would take the project's files over "
                           f"{_size(self.limits.project_bytes)}, the limit for one project",
                           at or Span(path, 1, 1, 1, 1), "too much to read",
                           help="a model of this size is unusual: check the imports for a mistake")
            return False
        return True

    def visit(self, path: str, at: Span | None) -> None:
        try:
            real = os.path.realpath(path)
        except ValueError:  # a NUL character in the path: ``read_bytes`` reports it
            read_bytes(path, self.sink, at)
            return
        if real in self.stack:
            cycle = [self.seen[r] for r in self.stack[self.stack.index(real):]] + [self.seen[real]]
            self.sink.emit("E103", "import cycle: " + " -> ".join(cycle), at or Span(path, 1, 1, 1, 1),
                           "closes the cycle", help="move what both files need into a third file that both import")
            return
        if real in self.seen:
            return
        if not self._within_limits(at):
            return
        self.seen[real] = path
        text = self.text(path, at)
        if text is None:
            return
        parsed = parse_source(text, path, self.limits)
        self.sources[path] = SourceFile(path, text, parsed.opaque)
        for d in parsed.diagnostics:
            self.sink.add(d)
        module = parsed.module
        if module is None:
            if parsed.partial is not None:
                self.partials[path] = parsed.partial
            return
        self.modules.append(module)
        self.stack.append(real)
        for imp in module.imports:
            target = self._resolve(path, imp)
            if target is not None:
                self.visit(target, imp.span)
        self.stack.pop()

    def _within_limits(self, at: Span | None) -> bool:
        if at is None:
            return True
        if len(self.stack) > self.limits.import_depth:  # (the root file is at depth 0, what it imports at 1)
            self.sink.emit("E008", f"imports are nested more than {self.limits.import_depth} deep", at,
                           "one import too deep", help="import the files a model needs from fewer levels: a file "
                           "may import several files")
            return False
        if len(self.seen) >= self.limits.files:
            self.sink.emit("E008", f"the project has more than {self.limits.files:,} files", at, "one file too many",
                           help="a model of this size is unusual: check the imports for a mistake")
            return False
        return True

    def _resolve(self, importer: str, imp: s.Import) -> str | None:
        """The path ``imp`` names, or None after reporting why it is not followed."""
        found = self.roots.resolve(importer, imp.path)
        if isinstance(found, Refusal):
            self.sink.emit(found.code, found.message, imp.path_span, found.label, help=found.help)
            return None
        return found


def load_project(root: str, sink: DiagnosticSink, *, roots: Roots | None = None, limits: Limits = DEFAULT_LIMITS,
                 overlay: Overlay | None = None) -> Project:
    """Parse ``root`` and its imports, confined to ``roots`` (default: the directory of ``root``).
    ``overlay`` gives the text of files held in memory: a mapping from paths, or a function of an
    absolute path that returns the text, or None to read the file from disk. Diagnostics go to
    ``sink``; the project holds what parsed."""
    if not root:
        sink.emit("E004", "no file name given", Span("<command line>", 1, 1, 1, 1), "cannot be read",
                  help="name a .vfy file, e.g. `verify check examples/navigation/navigation.vfy`")
        return Project(root, (), {})
    root = os.path.normpath(root)
    loading = _Loading(sink, roots if roots is not None else Roots.of_file(root), limits, overlay)
    loading.visit(root, None)
    return Project(root, tuple(loading.modules), loading.sources, loading.partials)


def project_from_text(text: str, path: str, sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> Project:
    """A one-file project from text in memory (imports are not followed)."""
    parsed = parse_source(text, path, limits)
    for d in parsed.diagnostics:
        sink.add(d)
    module = parsed.module
    if module is not None:
        for imp in module.imports:
            sink.emit("E004", f"imports are not followed for in-memory text: {imp.path}", imp.span,
                      "not followed", help="load the file from disk instead")
    return Project(path, (module,) if module else (), {path: SourceFile(path, text, parsed.opaque)},
                   {path: parsed.partial} if parsed.partial is not None else {})
