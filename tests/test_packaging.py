"""The installed package holds every module of the source tree (``pip install .`` lists packages
explicitly in pyproject.toml, so a new subpackage must be added there)."""
from __future__ import annotations

import tomllib

from .conftest import ROOT


def test_every_subpackage_is_installed():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    listed = set(config["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "verify").rglob("__init__.py")}
    assert found <= listed, f"missing from [tool.setuptools] packages: {sorted(found - listed)}"
