"""CARET (tier4/caret_analyze): import a ROS 2 architecture file, export chains as named paths.

``import_dirs(paths, system, sink)`` reads the architecture file (``*.yaml``; a directory is searched for
one) and gives it in verify's language: nodes as instances, callbacks as tasks bound to their
executors, topics and variable passings as connections, named paths as chains
(``to_vfy.import_architecture``). ``export.export_system`` writes a configured system's chains as
CARET named paths. specs/interop.md, "CARET", maps every construct.
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

from ...core.diagnostics import DiagnosticSink
from ...core.limits import DEFAULT_LIMITS, Limits
from ...core.source import SourceFile, Span
from .. import files_under
from .read import Architecture, read
from .to_vfy import Imported, import_architecture

NAME = "caret"
DESCRIPTION = "CARET architecture files (architecture.yaml)"
SUFFIXES = (".yaml", ".yml")


@dataclass
class Read:
    files: list[Architecture]
    sources: dict[str, SourceFile]


def read_files(paths: Sequence[str], sink: DiagnosticSink, limits: Limits = DEFAULT_LIMITS) -> Read:
    """Every architecture file named by ``paths`` (files, or directories searched recursively in name order)."""
    from ...core.fileaccess import area_of
    from ...frontend.loader import read_text as read_file

    area = area_of(paths)  # (a file found there that is a link leading out is refused: E006)
    found: list[str] = []
    for path in paths:
        if os.path.isdir(path):
            found += files_under(path, SUFFIXES)
        else:
            found.append(path)
    out = Read([], {})
    for path in found[:limits.files]:
        text = read_file(path, sink, out.sources, limits, area)
        if text is None:
            continue
        out.sources[path] = SourceFile(path, text)
        arch = read(text, path, sink, limits)
        if arch is not None:
            out.files.append(arch)
    if not found:
        sink.emit("E004", "no architecture file (*.yaml) under " + ", ".join(paths),
                  Span(paths[0] if paths else "<command line>", 1, 1, 1, 1), "nothing to read",
                  help="name the architecture.yaml that `Architecture.export` wrote")
    return out


def import_dirs(paths: Sequence[str], system: str | None, sink: DiagnosticSink,
                limits: Limits = DEFAULT_LIMITS) -> tuple[Imported | None, dict[str, SourceFile]]:
    """The architecture under ``paths`` as a system of verify's language named ``system`` (default: the
    file's name), or None after an error that leaves nothing to import; and the files read."""
    got = read_files(paths, sink, limits)
    if sink.has_errors:
        return None, got.sources
    if len(got.files) != 1:
        where = got.files[1].path if got.files else (paths[0] if paths else "<command line>")
        sink.emit("E105", f"{len(got.files)} architecture files under " + ", ".join(paths) + "; one is imported",
                  Span(where, 1, 1, 1, 2), "more than one", help="name the one architecture file to import")
        return None, got.sources
    return import_architecture(got.files[0], system, sink), got.sources


__all__ = ["DESCRIPTION", "NAME", "Imported", "Read", "import_dirs", "read_files"]
