"""Code generators: from a configured system to the code that runs it (specs/codegen.md).

A target is one module here (``ros1.py``, ``ros2.py``) with ``TARGET`` (its name on the command line), ``HELP``,
optionally ``unsupported(model) -> [(span, what, help)]`` (what of a system it cannot run with the
semantics verified: E602, and nothing is generated), optionally ``differs(model)`` likewise (what its
runtime would run otherwise than the analysis assumes: E604) and ``generate(model) -> Tree``: the files it
makes, each owned either by the generator (``glue``: rewritten on every run, never to be edited) or by
the user (``user``: written once, never overwritten: the generation gap). ``verify.gen.tree`` writes a
tree into a directory without losing anything a user wrote. The registry is the set of target modules;
a new target is one module.
"""
from __future__ import annotations

import importlib
from types import ModuleType

#: the targets ``verify gen`` offers
TARGETS = ("ros1", "ros2")


def target(name: str) -> ModuleType:
    """The module of target ``name``."""
    if name not in TARGETS:
        raise KeyError(name)
    return importlib.import_module(f"{__name__}.{name}")
