"""The fuzz targets (``fuzz.targets``): every seed and every regression input passes every stage, and a
short coverage-guided run under atheris finds nothing (docs/guide/untrusted.md, docs/contributing/fuzzing.md).

A finding of a long run (``python -m fuzz``), once fixed, is kept in ``tests/fuzz_regressions/TARGET/``
and replayed here through its target.
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from fuzz.seeds import seeds
from fuzz.targets import TARGETS, Finding, run

from .conftest import ROOT, in_ci

pytestmark = pytest.mark.slow  # (the quick loop leaves it out: docs/contributing/tests.md)

REGRESSIONS = ROOT / "tests" / "fuzz_regressions"
SEEDS = seeds()


def _regressions():
    for path in sorted(REGRESSIONS.glob("*/*")):
        yield pytest.param(path.parent.name, path, id=f"{path.parent.name}/{path.name}")


@pytest.mark.parametrize("target", sorted(TARGETS))
def test_every_seed_passes_every_stage(target):
    for _name, data in SEEDS.items():
        run(target, data)


@pytest.mark.parametrize("target,path", list(_regressions()))
def test_every_fuzz_finding_stays_fixed(target, path: Path):
    run(target, path.read_bytes())


def test_the_targets_report_what_they_are_for():
    # a broken invariant is a finding (the harness would save the input), not a silent pass
    from fuzz import targets

    with pytest.raises(Finding):
        targets._check(False, "example")
    with pytest.raises(Finding):
        targets._located([_unlocated()])


def _unlocated():
    from verify.core.diagnostics import DiagnosticSink
    from verify.core.source import NO_SPAN

    return DiagnosticSink().emit("E001", "x", NO_SPAN)


def test_a_short_coverage_guided_run_finds_nothing(tmp_path):
    if importlib.util.find_spec("atheris") is None:
        if in_ci():
            pytest.fail("atheris is not installed (the test extras install it)")
        pytest.skip("atheris is not installed: pip install -e '.[test]'")
    from fuzz.run import main

    assert main(["--smoke", "--out", str(tmp_path)]) == 0, (tmp_path / "summary.json").read_text()
    summary = (tmp_path / "summary.json").read_text()
    assert '"findings": 0' in summary
