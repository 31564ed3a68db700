"""What every generation target (`verify gen ros1`, `verify gen ros2`) keeps alike: a changed
configuration changes the parameter file only (specs/codegen.md §3)."""
from __future__ import annotations

import shutil

import pytest

from verify.cli import main

from .builders import project_files


@pytest.mark.parametrize("target", ["ros1", "ros2"])
def test_regenerating_after_synth_changes_only_the_parameter_file(target, navigation_models, tmp_path):
    models = navigation_models
    project = tmp_path / "out"
    holes = str(models / "navigation-holes.vfy")
    first, second = tmp_path / "first.vfy", tmp_path / "second.vfy"
    assert main(["synth", holes, "-o", str(first)]) == 0
    assert main(["synth", holes, "--objective", "latency:reactive", "-o", str(second)]) == 0
    shutil.copy(models / "components.vfy", tmp_path / "components.vfy")
    assert main(["gen", target, str(first), "-o", str(project)]) == 0
    before = project_files(project)
    assert main(["gen", target, str(second), "-o", str(project)]) == 0
    after = project_files(project)
    assert {p for p in after if after[p] != before.get(p)} == {"config/parameters.yaml"}
    assert set(after) == set(before)
