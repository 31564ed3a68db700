"""`arrival_cost`: the work an rclpy process does to take arrivals, charged as arrival tasks
(specs/timing.md §6.6, specs/codegen.md §9.5): the declaration, the tasks it adds, the analyses that charge
them (plain tasks, executors, multi-threaded executors), the simulators that run them, `prove`, `synth`
and `gen ros2`'s warning without it."""
from __future__ import annotations

import random
from fractions import Fraction as F

import pytest

import verify
from verify.cli import main
from verify.frontend.fmt import format_text
from verify.model.arrivals import arrival_tasks, with_arrivals
from verify.model.processes import Process, core_of, process_of, processes, subscriptions
from verify.prove import prove
from verify.prove.scenario import replay
from verify.prove.intsim import run_trace
from verify.synth import synthesize
from verify.timing import analyze

from .conftest import EXAMPLES
from .executor_systems import executor_system, mt_system
from .test_intsim import concrete_scenario
from .test_executors import no_run_beyond_the_bounds

MS = F(1, 1000)

PAIR = """\
component Sensor {
  out data : Scan
  task Read {
    produces data
    bcet 1 ms
    wcet 1 ms
  }
}

component Filter {
  in data : Scan
  task Smooth {
    reads data
    wcet 2 ms
  }
  task Log {
    wcet 1 ms
  }
}

system S {
  core cpu0
  core cpu1
  ARRIVALS
  instance sensor : Sensor on cpu0 {
    task Read priority 2 timer 10 ms
  }
  instance filter : Filter on cpu1 {
    task Smooth priority 2 trigger data
    task Log priority 1 timer 20 ms
  }
  connect sensor.data -> filter.data delay 1 ms
}
"""


def _model(text: str):
    result = verify.load_text(text, "main.vfy")
    assert result.ok, [(d.code, d.message) for d in result.diagnostics]
    return result.system()


def _pair(cost: str = "arrival_cost 500 us"):
    return _model(PAIR.replace("ARRIVALS", cost))


def _with_cost(text: str, cost: str) -> str:
    return text.replace("system S {\n", f"system S {{\n  arrival_cost {cost}\n", 1)


def test_the_declaration_is_a_time_kept_by_fmt():
    model = _pair()
    assert model.arrival_cost == F(1, 2000)
    text = PAIR.replace("ARRIVALS", "arrival_cost 500 us")
    assert format_text(text, "main.vfy") == (text, [])
    assert _pair("").arrival_cost is None


@pytest.mark.parametrize("cost, code", [("arrival_cost 2 Hz", "E302"), ("arrival_cost 0 ms", "E307"),
                                        ("arrival_cost 1 ms\n  arrival_cost 2 ms", "E212")])
def test_a_bad_declaration_is_a_located_error(cost, code):
    result = verify.load_text(PAIR.replace("ARRIVALS", cost), "main.vfy")
    found = [d for d in result.diagnostics if d.code == code]
    assert found and not result.ok and found[0].span.line in (24, 25)


def test_the_partition_is_that_of_gen_ros2():
    model = _model((EXAMPLES / "navigation" / "navigation-ros.vfy").read_text(encoding="utf-8")
                   .replace('import "components.vfy"',
                            (EXAMPLES / "navigation" / "components.vfy").read_text(encoding="utf-8")))
    from verify.gen.ros2 import units

    assert list(units(model)) == [p.label for p in processes(model)]
    oa = process_of(model.task("oa.OATask"))
    assert oa == Process("instance", "oa") and core_of(processes(model)[oa]) == "cpu1"
    assert subscriptions(model, processes(model)[oa]) == ("oa.scan", "oa.odom", "oa.path")  # (port order)
    assert process_of(model.task("base.RobotTask")).label == "base_RobotTask"


def test_one_arrival_task_per_process_and_in_port_above_every_task():
    model = _pair()
    added = arrival_tasks(model)
    assert [(t.id, t.core, t.priority, t.bcet, t.wcet, t.arrival) for t in added] == [
        ("filter.arrival[filter_Smooth]:data", "cpu1", 3, 0, F(1, 2000), True),
        ("filter.arrival[filter_Log]:data", "cpu1", 3, 0, F(1, 2000), True)]
    assert all(t.activation.single_port == "data" and t.reads == () and t.produces == () for t in added)
    assert with_arrivals(with_arrivals(model)) == with_arrivals(model)  # (once)
    plain = _pair("")
    assert with_arrivals(plain) is plain


def test_the_analysis_charges_each_arrival_to_the_tasks_of_its_core():
    """Smooth (2 ms) is released 1 ms after Read completes; the two arrival tasks of its core (one per
    process, each 0.5 ms) take the same value first: R = 2 + 2 · 0.5 ms. Log (1 ms, below Smooth) also
    waits for Smooth: 1 + 2 + 2 · 0.5 ms. Without the declaration neither is charged."""
    with_cost, without = analyze(_pair()), analyze(_pair(""))
    assert with_cost.task("filter.Smooth").wcrt == 3 * MS
    assert without.task("filter.Smooth").wcrt == 2 * MS
    assert with_cost.task("filter.Log").wcrt == 4 * MS and without.task("filter.Log").wcrt == 3 * MS
    assert with_cost.task("sensor.Read").wcrt == without.task("sensor.Read").wcrt == MS  # (its core takes none)
    assert with_cost.core("cpu1").utilisation == without.core("cpu1").utilisation + 2 * F(1, 2000) / (10 * MS)
    arrival = with_cost.task("filter.arrival[filter_Smooth]:data")
    assert arrival.response.deadline is None and arrival.wcrt == MS  # (the other process's value first)


def test_a_sporadic_task_takes_its_releases_by_message():
    text = PAIR.replace("ARRIVALS", "arrival_cost 1 ms").replace("task Log priority 1 timer 20 ms",
                                                                  "task Log priority 1 sporadic 50 ms .. 1 s")
    added = {t.id: t for t in arrival_tasks(_model(text))}
    release = added["filter.arrival[filter_Log]:release(Log)"]
    assert release.activation == _model(text).task("filter.Log").activation


def test_a_multi_threaded_callback_is_preempted_by_its_process_arrivals():
    """One worker on c1 (two threads), each callback in a mutually exclusive group of its own (§9.4):
    All (first in the processing order) has B = 5, W = 5 (carry) + 5 (Any) ms, so R = 5 + 10 + 5 = 20 ms
    without arrivals; with them (1 ms each; a's jitter 2 ms and R 2 ms, b's 1 ms and 2 ms) the least
    w = 20 + ⌈(w + 4)/20⌉ + ⌈(w + 3)/30⌉ ms = 23 ms, and its start-to-completion E = 5 + ⌈(E + 4)/20⌉ +
    ⌈(E + 3)/30⌉ = 7 ms. Any (after All): 25 ms; with them 25 + ⌈(w + 4)/20⌉ + ⌈(w + 3)/30⌉ = 29 ms."""
    text = """\
component Src {
  out o : Num
  task Tick {
    produces o
    wcet 1 ms
  }
}
component Fuse {
  in a : Num
  in b : Num
  in either = a | b
  task All {
    reads a
    wcet 5 ms
  }
  task Any {
    reads b
    wcet 5 ms
  }
}
system S {
  core c0
  core c1
  ARRIVALS
  executor mt multi_threaded 2 threads on c1 priority 4
  instance s1 : Src on c0 {
    task Tick priority 1 timer 20 ms
  }
  instance s2 : Src on c0 {
    task Tick priority 2 timer 30 ms
  }
  instance f : Fuse {
    group g1 mutually_exclusive
    group g2 mutually_exclusive
    task All executor mt group g1 trigger a
    task Any executor mt group g2 trigger b
  }
  connect s1.o -> f.a
  connect s2.o -> f.b
}
"""
    without = analyze(_model(text.replace("ARRIVALS", "")))
    cost = analyze(_model(text.replace("ARRIVALS", "arrival_cost 1 ms")))
    assert (without.task("f.All").wcrt, without.task("f.Any").wcrt) == (20 * MS, 25 * MS)
    assert (cost.task("f.All").wcrt, cost.task("f.Any").wcrt) == (23 * MS, 29 * MS)
    assert cost.task("f.All").response.hold == 7 * MS
    assert cost.core("c1").utilisation == without.core("c1").utilisation + F(1, 20) + F(1, 30)


def _arrivals_added(model):
    model = with_arrivals(model)
    assert any(t.arrival for t in model.tasks) or not model.links
    return model


def _no_run_beyond_the_bounds(text: str, seed: int) -> None:
    no_run_beyond_the_bounds(text, seed, _arrivals_added)


@pytest.mark.parametrize("seed", range(12))
def test_no_simulated_latency_beyond_the_bounds_with_arrivals_on_executors(seed):
    cost = random.Random(seed).choice(["300 us", "1 ms", "2 ms"])
    _no_run_beyond_the_bounds(_with_cost(executor_system(random.Random(seed)), cost), seed)


@pytest.mark.parametrize("seed", range(12))
def test_no_simulated_latency_beyond_the_bounds_with_arrivals_on_multi_threaded_executors(seed):
    cost = random.Random(seed).choice(["300 us", "1 ms", "2 ms"])
    _no_run_beyond_the_bounds(_with_cost(mt_system(random.Random(seed)), cost), seed)


@pytest.mark.parametrize("seed", range(6))
def test_the_integer_run_is_the_reference_run_with_arrivals(seed):
    model = with_arrivals(_model(_with_cost(mt_system(random.Random(seed)), "1 ms")))
    rng = random.Random(seed)
    scenario = concrete_scenario(model, rng, F(rng.randrange(20, 400), 1000))
    assert run_trace(model, scenario, 20_000) == replay(model, scenario, 20_000)


def test_prove_and_synth_charge_the_arrivals(tmp_path):
    model = _pair("arrival_cost 3 ms")
    proof = prove(model)
    deadlines = {v.name: v for v in proof.verdicts if v.kind == "deadline"}
    assert set(deadlines) == {"sensor.Read", "filter.Smooth", "filter.Log"}  # (none for an arrival task)
    text = (EXAMPLES / "navigation" / "navigation-holes.vfy").read_text(encoding="utf-8")
    (tmp_path / "components.vfy").write_text((EXAMPLES / "navigation" / "components.vfy").read_text("utf-8"), "utf-8")
    (tmp_path / "holes.vfy").write_text(text.replace("  core cpu1", "  arrival_cost 1 ms\n  core cpu1", 1), "utf-8")
    synthesized = synthesize(verify.load(str(tmp_path / "holes.vfy")), None)
    assert synthesized.ok
    assert main(["synth", str(tmp_path / "holes.vfy"), "-o", str(tmp_path / "filled.vfy")]) == 0
    filled = analyze(verify.load(str(tmp_path / "filled.vfy")).system(None))
    assert any(t.id.startswith("oa.arrival[") for t in filled.tasks)
    assert all(c.ok for chain in filled.chains for c in chain.specs)  # (the configuration holds, re-checked)


def test_gen_ros2_warns_without_the_declaration(tmp_path, capsys):
    (tmp_path / "s.vfy").write_text(PAIR.replace("ARRIVALS", ""), "utf-8")
    assert main(["gen", "ros2", str(tmp_path / "s.vfy"), "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert "warning[E605]" in err and "`filter_Smooth`, `filter_Log` take arrivals" in err
    (tmp_path / "s.vfy").write_text(PAIR.replace("ARRIVALS", "arrival_cost 1 ms"), "utf-8")
    assert main(["gen", "ros2", str(tmp_path / "s.vfy"), "-o", str(tmp_path / "out")]) == 0
    assert "E605" not in capsys.readouterr().err


def test_the_other_commands_show_the_arrival_tasks(tmp_path, capsys):
    (tmp_path / "s.vfy").write_text(PAIR.replace("ARRIVALS", "arrival_cost 1 ms"), "utf-8")
    assert main(["report", "--budget", "20", "-o", str(tmp_path / "r.html"), str(tmp_path / "s.vfy")]) == 0
    assert "filter.arrival[filter_Smooth]:data" in (tmp_path / "r.html").read_text("utf-8")
    for command in (["analyze", "--explain"], ["graph", "--format", "dot"], ["prove", "--format", "json"]):
        assert main([*command, str(tmp_path / "s.vfy")]) == 0, command
    assert "arrival[filter_Log]:data" in capsys.readouterr().out
