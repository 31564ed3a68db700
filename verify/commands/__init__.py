"""The commands of the command line, one module each (``verify.cli`` builds the argument parser from them).

A command module holds ``HELP`` (one line), ``RESULT`` (the kind of report it renders, whose formats
``verify.outputs`` lists for ``--format``; None for a command without one), ``MODEL`` (it reads a model
FILE and takes ``--root``/``--include``), ``SYSTEM`` (it takes ``--system``), ``add_arguments(parser)``
for its own options and ``run(args) -> int`` (the exit code, ``common``); optionally ``FILES`` (FILE is one
or more paths) and ``PARSER`` (``args.parser`` is the whole command line's parser). A new command is one
module listed in ``COMMANDS``.
"""
from __future__ import annotations

import importlib
from types import ModuleType

#: the commands, in the order ``verify --help`` lists them
COMMANDS = ("check", "analyze", "synth", "prove", "trace", "gen", "graph", "report", "import", "export", "lsp", "fmt",
            "explain", "completion")
#: a command whose name is a Python keyword lives in ``NAME_``
_MODULES = {"import": "import_"}


def command(name: str) -> ModuleType:
    """The module of command ``name``."""
    return importlib.import_module(f"{__name__}.{_MODULES.get(name, name)}")
