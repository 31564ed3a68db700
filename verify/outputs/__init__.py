"""The output registry: one renderer per result kind and format, each in its own module here.

A module ``KIND_FORMAT.py`` (``analysis_json.py``, ``proof_sarif.py``) renders a :class:`Report` of that
kind in that format with a function ``render(report) -> Output``. The registry is the set of these
modules: ``formats(kind)`` lists them without importing any (a command's ``--format`` choices come from
it, and the command line stays quick to start), ``render`` imports the one it needs. A new output format
of a result is one new module.

Kinds: ``diagnostics`` (a model that does not load: every command but ``prove`` reports it this way),
``check``, ``analysis``, ``synthesis``, ``proof``.
"""
from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Mapping

from ..core.diagnostics import Diagnostic
from ..core.source import SourceFile

#: the format every kind has and every command starts with
DEFAULT_FORMAT = "text"


@dataclass(frozen=True)
class Report:
    """What a command produced, for a renderer: its result (None when the input was invalid), the
    diagnostics to show with it, the sources they point into, the file the command ran on, the model
    it ran on, and what else the kind's renderers take (``extra``)."""

    kind: str
    file: str
    diagnostics: tuple[Diagnostic, ...] = ()
    sources: Mapping[str, SourceFile] = field(default_factory=dict)
    result: Any = None
    model: Any = None
    extra: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Output:
    """A rendered report: what goes to standard output (or the ``-o`` file) and to standard error."""

    stdout: str = ""
    stderr: str = ""


def formats(kind: str) -> tuple[str, ...]:
    """The formats of ``kind``, ``text`` first, then by name."""
    found = sorted(name[len(kind) + 1:] for _, name, _ in pkgutil.iter_modules(__path__)
                   if name.startswith(kind + "_"))
    return tuple(sorted(found, key=lambda f: (f != DEFAULT_FORMAT, f)))


def render(kind: str, fmt: str, report: Report) -> Output:
    """``report`` rendered by the module ``KIND_FORMAT``."""
    if fmt not in formats(kind):
        raise KeyError(f"no {fmt} output for {kind}")
    module = importlib.import_module(f"{__name__}.{kind}_{fmt}")
    out: Output = module.render(report)
    return out
