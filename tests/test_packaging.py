"""The installed package holds every module of the source tree (``pip install .`` lists packages
explicitly in pyproject.toml, so a new subpackage must be added there)."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from .conftest import ROOT, in_ci


def test_every_subpackage_is_installed():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    listed = set(config["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "verify").rglob("__init__.py")}
    assert found <= listed, f"missing from [tool.setuptools] packages: {sorted(found - listed)}"


def _config() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_the_distribution_has_a_name_of_its_own_and_the_readme_installs_it():
    """`verify` on the package index is an unrelated library: the distribution is `verify-timing`, and
    the installed metadata says so (the import package and the commands stay `verify`)."""
    from importlib.metadata import distribution

    assert _config()["project"]["name"] == "verify-timing"
    dist = distribution("verify-timing")
    assert {ep.name for ep in dist.entry_points if ep.group == "console_scripts"} >= {"verify", "synth", "prove"}
    assert "verify-timing" in (ROOT / "README.md").read_text(encoding="utf-8")


def test_version_is_one_number_everywhere(capsys):
    """`verify --version` (and `synth --version`, `prove --version`) print the package's version, the one
    the installed metadata holds, with those of the libraries results depend on."""
    import sys
    from importlib.metadata import version

    import pytest

    import verify
    from verify import cli

    assert version("verify-timing") == verify.__version__
    assert cli.main(["--version"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"verify {verify.__version__} (distribution verify-timing; Python ")
    assert f"z3-solver {version('z3-solver')}" in out and f"lark {version('lark')}" in out
    for script in (cli.synth_main, cli.prove_main):
        saved = sys.argv
        sys.argv = ["x", "--version"]
        try:
            with pytest.raises(SystemExit) as exit_:
                script()
        finally:
            sys.argv = saved
        assert exit_.value.code == 0 and capsys.readouterr().out == out


def test_license_file_matches_the_metadata():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License") and "Permission is hereby granted, free of charge" in text
    project = _config()["project"]
    assert project["license"] == {"text": "MIT"}
    assert "License :: OSI Approved :: MIT License" in project["classifiers"]


def test_the_quick_loop_is_documented_and_leaves_out_the_slow_tests():
    """`pytest -m "not slow"`: the marker is registered, the README gives the command, and the slowest
    tests of the suite carry it."""
    from . import test_fuzz, test_static, test_synth, test_synth_properties

    assert any(m.startswith("slow:") for m in _config()["tool"]["pytest"]["ini_options"]["markers"])
    assert 'python3 -m pytest -m "not slow"' in (ROOT / "README.md").read_text(encoding="utf-8")
    marked = [test_synth.test_navigation_optimum_agrees_with_brute_force_over_the_pruned_space,
              test_synth_properties.test_synth_agrees_with_brute_force]
    assert all(any(m.name == "slow" for m in getattr(f, "pytestmark", [])) for f in marked)
    assert all(m.name == "slow" for m in (test_fuzz.pytestmark, test_static.pytestmark))


def test_every_data_file_of_a_package_is_installed():
    """Files a package reads at run time (the C++ runtime `verify gen ros1` copies) are package data."""
    from fnmatch import fnmatch

    data = _config()["tool"]["setuptools"]["package-data"]
    runtime = ROOT / "verify" / "gen" / "ros1_runtime"
    files = [p.relative_to(ROOT / "verify" / "gen").as_posix() for p in runtime.rglob("*") if p.is_file()]
    assert files
    unlisted = [f for f in files if not any(fnmatch(f, pattern) for pattern in data.get("verify.gen", []))]
    assert not unlisted, f"missing from [tool.setuptools.package-data] verify.gen: {unlisted}"


#: what a clone's root holds that the installed package must not need (the tests and data stay behind)
_CLONE = ("verify", "grammar", "specs", "examples", "pyproject.toml")


def _installed_venv(where):
    """A virtual environment with verify installed from this tree as `pip install .` does it (a built
    wheel, not editable), and the dependencies (lark, z3, ...) of the running interpreter on its path, but
    none of that interpreter's .pth files (an editable install there would hide what is tested)."""
    import subprocess
    import sys
    import venv

    import lark
    import networkx
    import z3

    venv.create(where, with_pip=False)
    python = where / "bin" / "python"
    site = next((where / "lib").glob("python3*/site-packages"))
    deps = sorted({str(Path(m.__file__).resolve().parent.parent) for m in (lark, networkx, z3)})
    (site / "deps.pth").write_text("\n".join(deps) + "\n", encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps",
                           str(ROOT)], capture_output=True, text=True, timeout=600)
    if done.returncode != 0:  # (the build needs setuptools and wheel from the package index)
        message = f"cannot build and install verify: {done.stderr.strip()[-400:]}"
        if in_ci():
            pytest.fail(message)
        pytest.skip(message)
    return python


@pytest.mark.slow
def test_a_non_editable_install_works_from_the_clone_root(tmp_path):
    """`pip install .`, then `python -m verify` and `import verify` in the clone root: there the source
    tree's `verify/` comes first on the path, before the installed package, and it has no `verify.grammar`
    or `verify.specs` (pyproject.toml maps them from `grammar/` and `specs/`)."""
    import shutil
    import subprocess

    python = _installed_venv(tmp_path / "venv")
    clone = tmp_path / "clone"
    clone.mkdir()
    for name in _CLONE:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, clone / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(ROOT / name, clone / name)

    def run(*argv):
        return subprocess.run([str(python), *argv], cwd=clone, capture_output=True, text=True, timeout=120,
                              env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)})

    version = run("-m", "verify", "--version")
    assert version.returncode == 0 and version.stdout.startswith("verify "), version.stderr
    check = run("-m", "verify", "check", "examples/navigation/navigation.vfy")
    assert check.returncode == 0, check.stderr
    explain = run("-m", "verify", "explain", "E101")
    assert explain.returncode == 0 and explain.stdout.startswith("## E101"), explain.stderr
    snippet = run("-c", "import verify; r = verify.load('examples/navigation/navigation.vfy'); "
                        "print(verify.__file__); print(r.ok, len(r.system().tasks))")
    assert snippet.returncode == 0, snippet.stderr
    where, result = snippet.stdout.splitlines()
    assert Path(where).resolve().is_relative_to(clone.resolve())  # the shadowing this test is about
    assert result.split()[0] == "True" and int(result.split()[1]) > 0


def test_nothing_reads_beside_the_repository():
    """The repository stands alone: no code, test, example, fuzz seed, benchmark or script refers to a
    directory beside the clone (the test data is copied in, with its origin and licence)."""
    beside = ("../" + "shared", 'parent / "' + 'shared"')
    found = [str(p.relative_to(ROOT)) for top in ("verify", "tests", "fuzz", "benchmarks", "examples", "scripts")
             for p in (ROOT / top).rglob("*") if p.is_file() and "out" not in p.relative_to(ROOT).parts[:2]
             and p.suffix != ".pyc" and any(b in p.read_text(encoding="utf-8", errors="replace") for b in beside)]
    assert not found
