"""The Autoware reference-system example (examples/autoware-reference): it analyses with a bound for every
task, proves, synthesizes, and its bounds hold against the simulator."""
from __future__ import annotations

import random
from fractions import Fraction

import pytest

import verify
from verify.cli import main
from verify.prove.sim import random_scenario, simulate
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


# ------------------------------------------------------------------ on ROS 2 executors (specs/timing.md §9)


def test_the_executor_set_ups_have_the_reference_systems_shape():
    """The same 24 nodes and chains, every callback bound to an executor: four in the prioritized
    set-up (front, rear and inner hot path, the rest), one in the single-threaded set-up."""
    base = _model()
    for name, executors in (("autoware-executors.vfy", 4), ("autoware-single-executor.vfy", 1),
                            ("autoware-multi-threaded.vfy", 1)):
        model = verify.load(str(AUTOWARE / name)).system()
        assert [t.id for t in model.tasks] == [t.id for t in base.tasks]
        assert [c.tasks for c in model.chains] == [c.tasks for c in base.chains]
        assert len(model.executors) == executors and all(t.executor is not None for t in model.tasks)
    prioritized = verify.load(str(AUTOWARE / "autoware-executors.vfy")).system()
    assert [t.id for t in prioritized.callbacks("inner")] == [
        "point_cloud_fusion.Fuse", "ray_ground_filter.Process", "euclidean_cluster_detector.Process0",
        "euclidean_cluster_detector.Process1", "object_collision_estimator.Process"]


def test_the_prioritized_executors_prove_the_hot_path(capsys):
    """On its own executor the hot path's pipeline is bounded stage by stage (each stage is not charged
    for the stages its output releases: the causal caps of §9.3): both hot-path specs are proved by
    the bound. The executor of every other node is 90 % busy, and its callbacks are bounded by the
    polling rounds; that bound does not prove the localization and control specs."""
    analysis = analyze(verify.load(str(AUTOWARE / "autoware-executors.vfy")).system())
    assert [d.code for d in diagnostics_of(analysis) if d.severity.value == "error"] == []
    hot = analysis.chain("hot_path")
    assert (hot.bound("reaction_time").worst, hot.bound("data_age").worst) == (Fraction(3604, 10000),
                                                                              Fraction(24025, 100000))
    assert analysis.task("object_collision_estimator.Process").wcrt == Fraction(5, 100)
    assert analysis.task("behavior_planner.Plan").response.rule == "single_threaded executor, polling rounds"
    assert main(["prove", "--budget", "50", str(AUTOWARE / "autoware-executors.vfy")]) == 3  # undecided: the rest
    out = capsys.readouterr().out
    out = " ".join(out.split())
    assert "chain hot_path: reaction time proved bound <= 400 ms" in out
    assert "chain control: reaction time undecided" in out


def test_one_executor_for_every_node_is_overloaded(capsys):
    """The single-threaded set-up asks 151.67 % of its thread (E311): its callbacks miss activations,
    which they absorb, so each is still bounded — by the polling rounds: the round in progress and the
    callbacks before it in the next, from 170.9 ms for the first timer to 341.6 ms for the last
    subscription. ``prove`` finds runs that break the hot path's specs (and the control chain's), each a
    counterexample that replays."""
    analysis = analyze(verify.load(str(AUTOWARE / "autoware-single-executor.vfy")).system())
    assert [d.code for d in diagnostics_of(analysis) if d.severity.value == "error"] == ["E311"]
    assert analysis.core("cpu0").utilisation == Fraction(15167, 10000)
    bounds = sorted(t.wcrt for t in analysis.tasks)
    assert (bounds[0], bounds[-1]) == (Fraction(1709, 10000), Fraction(3416, 10000))
    assert all(t.response.rule == "single_threaded executor, polling rounds" for t in analysis.tasks)
    assert main(["prove", "--budget", "50", str(AUTOWARE / "autoware-single-executor.vfy")]) == 1
    out = capsys.readouterr().out
    out = " ".join(out.split())
    assert "chain hot_path: reaction time violated search <= 400 ms" in out
    assert "chain control: reaction time violated" in out


def test_one_multi_threaded_executor_bounds_every_callback(capsys):
    """The multi-threaded set-up (specs/timing.md §9.4): four workers, every node in its default
    (mutually exclusive) group, the cluster detector's two subscriptions in a group each. Every callback
    has a bound (the work of one job of every other callback, and one more of those before it, over four
    workers); the chains' bounds do not prove their specs, and ``prove`` cannot decide them (execution
    times are ranges), though no run comes near."""
    model = verify.load(str(AUTOWARE / "autoware-multi-threaded.vfy")).system()
    analysis = analyze(model)
    assert [d.code for d in diagnostics_of(analysis) if d.severity.value == "error"] == []
    assert analysis.core("cpu2").utilisation == Fraction(379175, 1000000)
    assert analysis.task("object_collision_estimator.Process").wcrt == Fraction(8785, 100000)
    hot = analysis.chain("hot_path")
    assert (hot.bound("reaction_time").worst, hot.bound("data_age").worst) == (Fraction(782875, 1000000),
                                                                              Fraction(486825, 1000000))
    assert main(["prove", "--budget", "20", str(AUTOWARE / "autoware-multi-threaded.vfy")]) == 3
    assert "25 proved, 0 violated, 4 undecided" in capsys.readouterr().out


def test_in_the_default_group_the_second_subscription_of_a_node_can_starve(tmp_path):
    """With the reference system's own groups (each node's default group) the cluster detector's
    settings subscription comes after its detection subscription in one mutually exclusive group: it
    can starve (Teper et al., EMSOFT 2024), and it is reported without a bound, with the remedy."""
    text = (AUTOWARE / "autoware-multi-threaded.vfy").read_text()
    grouped = """    group detection mutually_exclusive
    group settings mutually_exclusive
    task Process0 executor mt group detection trigger input0
    task Process1 executor mt group settings trigger input1"""
    assert grouped in text
    (tmp_path / "components.vfy").write_text((AUTOWARE / "components.vfy").read_text())
    path = tmp_path / "default-groups.vfy"
    path.write_text(text.replace(grouped, "    task Process0 executor mt trigger input0\n"
                                          "    task Process1 executor mt trigger input1"))
    analysis = analyze(verify.load(str(path)).system())
    settings = analysis.task("euclidean_cluster_detector.Process1").response
    assert settings.wcrt is None and "may starve: `euclidean_cluster_detector.Process0` comes before it" in (
        settings.failure)
    [diag] = [d for d in diagnostics_of(analysis) if "Process1" in d.message]
    assert diag.code == "E312" and "callback group of its own" in diag.help


@pytest.mark.parametrize("name", ["autoware-executors.vfy", "autoware-single-executor.vfy",
                                  "autoware-multi-threaded.vfy"])
def test_the_executor_bounds_hold_against_the_simulator(name):
    model = verify.load(str(AUTOWARE / name)).system()
    analysis = analyze(model)
    for run in range(3):
        trace = simulate(model, random_scenario(model, random.Random(f"autoware/{run}"), Fraction(2)))
        assert bound_violations(model, trace, analysis) == []
