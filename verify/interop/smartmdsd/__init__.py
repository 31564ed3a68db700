"""SmartMDSD (the Eclipse toolchain of Lotz et al.'s meta-model): import its models, export a configuration.

``import_dirs(paths, system, sink)`` reads the ``.component``, ``.componentArch``, ``.activityArch`` and
``.causeEffectChain`` files under ``paths`` (directories are searched recursively, in name order) and
gives the chosen system in verify's language; ``export.export_system`` writes a configured system back.
specs/interop.md maps every construct.
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

from ...core.diagnostics import DiagnosticSink
from ...core.limits import DEFAULT_LIMITS, Limits
from ...core.source import SourceFile, Span
from .. import files_under
from .read import KINDS, Files, read_text
from .to_vfy import Imported, import_system

NAME = "smartmdsd"
DESCRIPTION = "SmartMDSD models (.component, .componentArch, .activityArch, .causeEffectChain)"


@dataclass
class Read:
    files: Files
    sources: dict[str, SourceFile]


def model_files(paths: Sequence[str], sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> list[str]:
    """The model files named by ``paths`` (files, or directories searched recursively, in name order;
    symbolic links to directories are not followed)."""
    found: list[str] = []
    for path in paths:
        if os.path.isdir(path):
            found += files_under(path, KINDS)
        elif path.endswith(KINDS) or os.path.exists(path):
            found.append(path)
        else:
            sink.emit("E004", f"no such file or directory: {path}", Span(path, 1, 1, 1, 1), "cannot be read",
                      help="name the directories that hold the SmartMDSD models")
    if len(found) > limits.files:
        sink.emit("E008", f"{len(found):,} model files, more than {limits.files:,}, the limit of one run",
                  Span(paths[0] if paths else "<command line>", 1, 1, 1, 1), "too many files",
                  help="name the directories of one system and its components")
        return []
    return found


def read_files(paths: Sequence[str], sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> Read:
    from ...core.fileaccess import area_of
    from ...frontend.loader import read_text as read_file

    area = area_of(paths)  # (a file found there that is a link leading out is refused: E006)
    files, sources = Files(), dict[str, SourceFile]()
    total = 0
    for path in model_files(paths, sink, limits):
        if not path.endswith(KINDS):
            sink.emit("E004", f"{path} is not a SmartMDSD model file (expected one of {', '.join(KINDS)})",
                      Span(path, 1, 1, 1, 1), "not a model file", help="name the model files or their directory")
            continue
        text = read_file(path, sink, sources, limits, area)
        if text is None:
            continue
        total += len(text)
        if total > limits.project_bytes:
            sink.emit("E008", f"the model files are larger than {limits.project_bytes // (1024 * 1024)} MiB together",
                      Span(path, 1, 1, 1, 1), "too large", help="name the directories of one system only")
            break
        sources[path] = SourceFile(path, text)
        read_text(text, path, files, sink)
    return Read(files, sources)


def import_dirs(paths: Sequence[str], system: str | None, sink: DiagnosticSink,
                limits: Limits = DEFAULT_LIMITS) -> tuple[Imported | None, dict[str, SourceFile]]:
    """The system under ``paths`` in verify's language (None after an error that leaves nothing to import:
    a file that cannot be read or parsed, no system or several), and the files read (for snippets)."""
    read = read_files(paths, sink, limits)
    if sink.has_errors:
        return None, read.sources
    return import_system(read.files, system, sink), read.sources


__all__ = ["DESCRIPTION", "NAME", "Imported", "Read", "import_dirs", "read_files"]
