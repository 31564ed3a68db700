"""Other tools' models: importers and exporters, one module (or package) per tool.

A tool is a module ``verify.interop.NAME`` with ``NAME``, ``DESCRIPTION`` and ``import_dirs(paths,
system, sink)`` (an importer) and/or a module ``verify.interop.NAME.export`` with ``export_system``
(an exporter). A new tool is one package plus its tests; specs/interop.md maps its constructs.
"""
from __future__ import annotations

import importlib
from types import ModuleType

#: the tools whose models ``verify import`` reads
IMPORTERS = ("smartmdsd", "caret")
#: the tools whose models ``verify export`` writes
EXPORTERS = ("smartmdsd", "caret")


def files_under(directory: str, suffixes: tuple[str, ...]) -> list[str]:
    """The files under ``directory`` whose names end with one of ``suffixes``, searched recursively in
    name order (symbolic links to directories are not followed)."""
    import os

    found: list[str] = []
    for root, dirs, names in os.walk(directory):
        dirs.sort()
        found += [os.path.join(root, n) for n in sorted(names) if n.endswith(suffixes)]
    return found


def tool(name: str) -> ModuleType:
    return importlib.import_module(f"{__name__}.{name}")


def exporter(name: str) -> ModuleType:
    return importlib.import_module(f"{__name__}.{name}.export")
