"""The lowest versions the dependency ranges of pyproject.toml allow still pass the tests that use those
libraries: a virtual environment with exactly the lower bounds (on top of the installed ones, so that
only the ranged libraries change) runs them. The newest allowed versions are what the README's install
picks, and the rest of the suite runs on them."""
from __future__ import annotations

import os
import re
import subprocess
import tomllib
import venv

import pytest

from .conftest import ROOT, in_ci

#: the tests that exercise the ranged libraries: Lark (the parser, its recovery, fmt, the front end),
#: networkx (validation, the synthesis structure), end to end on the examples, pygls (the language
#: server, with a real client) and PyYAML (CARET's architecture files)
SUBSET = ("tests/test_parse.py", "tests/test_fmt.py", "tests/test_frontend.py", "tests/test_examples.py",
          "tests/test_lsp.py", "tests/test_caret.py")
VENV = ROOT / "tests" / "out" / "lowest-venv"


def lower_bounds() -> dict[str, str]:
    """Each dependency with a range, and its lower bound (``>=X``)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    found = {}
    for spec in config["project"]["dependencies"]:
        m = re.fullmatch(r"([A-Za-z0-9_.-]+)\s*>=\s*([^,\s]+)(,.*)?", spec)
        if m:
            found[m.group(1)] = m.group(2)
    return found


def _python() -> str:
    return str(VENV / ("Scripts" if os.name == "nt" else "bin") / "python")


@pytest.mark.slow
def test_the_lowest_allowed_versions_pass():
    bounds = lower_bounds()
    assert set(bounds) == {"lark", "networkx", "pygls", "PyYAML"}
    venv.create(VENV, system_site_packages=True, with_pip=True, clear=not VENV.exists())
    pins = [f"{name}=={version}" for name, version in sorted(bounds.items())]
    install = subprocess.run([_python(), "-m", "pip", "install", "-q", "--no-deps", *pins],
                             capture_output=True, text=True, check=False)
    if install.returncode != 0:
        message = f"cannot install {', '.join(pins)}: {install.stderr.strip()[-400:]}"
        if in_ci():
            pytest.fail(message)
        pytest.skip(message)  # (no package index outside CI: CI runs it)
    versions = subprocess.run([_python(), "-c", "import lark, networkx, yaml; from importlib.metadata import "
                               "version; print(lark.__version__, networkx.__version__, version('pygls'), "
                               "yaml.__version__)"],
                              capture_output=True, text=True, check=True).stdout.split()
    assert versions == [bounds["lark"], bounds["networkx"], bounds["pygls"], bounds["PyYAML"]]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    # (`-o addopts=`: in one process, without the suite's pytest-xdist options)
    run = subprocess.run([_python(), "-m", "pytest", "-o", "addopts=", "-q", "-p", "no:cacheprovider", "-x", *SUBSET],
                         cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]  # (5 if nothing ran)
