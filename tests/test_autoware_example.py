"""The Autoware reference-system example (examples/autoware-reference): it analyses with a bound for every
task, proves, synthesizes, and its bounds hold against the simulator."""
from __future__ import annotations

import random
from fractions import Fraction

import verify
from verify.cli import main
from verify.sim import random_scenario, simulate
from verify.timing import analyze, diagnostics_of

from .conftest import EXAMPLES
from .test_timing import bound_violations

AUTOWARE = EXAMPLES / "autoware-reference"


def _model():
    return verify.load(str(AUTOWARE / "autoware.vfy")).system()


def test_the_shape_of_the_reference_system():
    model = _model()
    assert len(model.instances) == 24 and len(model.tasks) == 25  # the intersection node has two callbacks
    joins = [t for t in model.tasks if t.activation.kind == "trigger" and t.activation.mode == "and"]
    assert len(joins) == 5
    planner = model.task("behavior_planner.Plan")
    assert planner.activation.period == Fraction(1, 10) and len(planner.reads) == 6


def test_every_task_has_a_bound_and_every_spec_is_proved(capsys):
    analysis = analyze(_model())
    assert list(diagnostics_of(analysis)) == []
    assert all(t.wcrt is not None for t in analysis.tasks)
    assert main(["analyze", str(AUTOWARE / "autoware.vfy")]) == 0
    assert main(["prove", str(AUTOWARE / "autoware.vfy")]) == 0
    assert "proved  bound   <= 400 ms  270.6 ms" in capsys.readouterr().out


def test_synth_chooses_the_planner_period(capsys):
    assert main(["synth", str(AUTOWARE / "autoware-holes.vfy")]) == 0
    captured = capsys.readouterr()
    assert "behavior_planner.Plan  timer ? in 50 ms .. 200 ms step 10 ms  ->  timer 200 ms" in captured.err
    assert "task Plan priority 30 timer 200 ms" in captured.out


def test_the_bounds_hold_against_the_simulator():
    model = _model()
    for run in range(4):
        trace = simulate(model, random_scenario(model, random.Random(f"autoware/{run}"), Fraction(2)))
        assert bound_violations(model, trace) == []
