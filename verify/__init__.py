"""verify: formal verification of the timing of component-based robotics software.

The public façade: ``load`` / ``load_text`` return a :class:`LoadResult` holding the parsed project,
every diagnostic and the semantic model of each valid system. See docs/guide/library.md. The names are
imported when first used (PEP 562), so that a command that needs none of the front end (``verify
--help``, ``--version``) starts without it.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .api import LoadResult, SelectionError, load, load_text
    from .core.diagnostics import Diagnostic, Label, Severity

__all__ = ["Diagnostic", "Label", "LoadResult", "SelectionError", "Severity", "load", "load_text"]
__version__ = "0.1.0"

#: each public name and the module that defines it
_HOME = {"LoadResult": "api", "SelectionError": "api", "load": "api", "load_text": "api",
         "Diagnostic": "diagnostics", "Label": "diagnostics", "Severity": "diagnostics"}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        value = getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'verify' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
