"""Other tools' models: importers and exporters, one module (or package) per tool.

A tool is a module ``verify.interop.NAME`` with ``NAME``, ``DESCRIPTION`` and ``import_dirs(paths,
system, sink)`` (an importer) and/or a module ``verify.interop.NAME.export`` with ``export_system``
(an exporter). A new tool is one package plus its tests; specs/interop.md maps its constructs.
"""
from __future__ import annotations

import importlib
from types import ModuleType

#: the tools whose models ``verify import`` reads
IMPORTERS = ("smartmdsd",)
#: the tools whose models ``verify export`` writes
EXPORTERS = ("smartmdsd",)


def tool(name: str) -> ModuleType:
    return importlib.import_module(f"{__name__}.{name}")


def exporter(name: str) -> ModuleType:
    return importlib.import_module(f"{__name__}.{name}.export")
