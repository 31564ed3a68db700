"""The data files verify reads at run time: the grammar (``grammar/``) and the specs (``specs/``).

An install maps them to the packages ``verify.grammar`` and ``verify.specs`` (pyproject.toml,
``package-dir``). Run from the repository itself — ``python -m verify`` or ``import verify`` with the
clone as the working directory, which puts the source tree's ``verify/`` first on the path, before
whatever is installed — there are no such packages, and the files are read from the directories beside
``verify/`` instead.
"""
from __future__ import annotations

from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path

__all__ = ["data_dir", "data_text"]


def data_dir(package: str) -> Traversable:
    """The files of ``verify.PACKAGE`` (``grammar`` or ``specs``): installed, else the source tree's."""
    try:
        return resources.files(f"verify.{package}")
    except ModuleNotFoundError:
        source = Path(__file__).resolve().parents[2] / package  # (beside the package: verify/core/ -> the clone)
        if not source.is_dir():
            raise
        return source


def data_text(package: str, name: str) -> str:
    """The text of file NAME of ``verify.PACKAGE``."""
    return data_dir(package).joinpath(name).read_text(encoding="utf-8")
