"""The multi-threaded executor and callback groups (specs/timing.md §9.4): what a run does, job by
job, in both simulators; the bounds against runs of random systems and against ``prove``'s exact
search; ``synth`` against brute force; the language around them."""
from __future__ import annotations

import random
from fractions import Fraction as F

import pytest

import verify
from verify.prove.intsim import run_trace
from verify.prove.measure import measure
from verify.prove.scenario import measure_reference, replay
from verify.prove.sim import Scenario, simulate
from verify.timing import analyze

from .executor_systems import mt_system
from .test_executors import _model, _times, exact_between_runs_and_bound, no_run_beyond_the_bounds, rigid_system
from .test_intsim import _targets, concrete_scenario
from .test_timing import MS


def _two(group_x: str, group_y: str, groups: str = "") -> str:
    """Two timer callbacks of one node released at 0 (x, 3 ms) and 1 ms (y, 1 ms) on two workers."""
    return f"""
component N {{
  task X {{ wcet 3 ms bcet 3 ms }}
  task Y {{ wcet 1 ms bcet 1 ms }}
}}
system S {{
  core c0
  core c1
  executor e multi_threaded on c0, c1 priority 5
  instance n : N {{
    {groups}
    task X executor e {group_x} timer 10 ms phase 0 ms
    task Y executor e {group_y} timer 10 ms phase 1 ms
  }}
}}
"""


@pytest.mark.parametrize("groups, x, y, start", [
    ("", "", "", 3),  # the node's default group is mutually exclusive: y waits for x
    ("group a mutually_exclusive group b mutually_exclusive", "group a", "group b", 1),
    ("group r reentrant", "group r", "group r", 1),
])
def test_workers_run_callbacks_of_different_groups_at_once(groups, x, y, start):
    model = _model(_two(x, y, groups))
    trace = simulate(model, Scenario(F(10, 1000)))
    assert _times(trace, "n.X")[0] == (0, 0, 3)
    assert _times(trace, "n.Y")[0] == (1, start, start + 1)
    scenario = concrete_scenario(model, random.Random(0), F(10, 1000))
    assert run_trace(model, scenario, 1000) == replay(model, scenario, 1000)


STARVING = """
component N {
  task X { wcet 3 ms bcet 3 ms }
  task Y { wcet 1 ms bcet 1 ms }
}
component B { task Run { wcet 1 ms bcet 1 ms } }
system S {
  core c0
  core c1
  executor e multi_threaded on c0, c1 priority 5
  instance n : N {
    task X executor e timer 3 ms phase 0 ms
    task Y executor e @Y@ timer 4 ms phase 1 ms
  }
  instance z : B { task Run executor e timer 2 ms phase 1/2 ms }
}
"""


def test_a_callback_behind_another_of_its_mutually_exclusive_group_can_starve():
    """Teper et al., EMSOFT 2024: every poll with the node's group free finds x pending again and runs
    it first, and every poll while x runs leaves y out; y never starts though a worker idles half the
    time. The analysis gives y no bound and says why; a group of its own gives it one."""
    model = _model(STARVING.replace("@Y@", ""))
    trace = simulate(model, Scenario(F(60, 1000)))
    assert [j.start for j in trace.jobs["n.Y"]] == [None]
    assert [(j.release, j.start) for j in trace.jobs["n.X"]] == [(3 * k * MS, 3 * k * MS) for k in range(20)]
    result = verify.load_text(STARVING.replace("@Y@", ""), "starve.vfy")
    analysis = analyze(result.system())
    assert analysis.task("n.Y").wcrt is None
    assert "may starve: `n.X` comes before it" in analysis.task("n.Y").response.failure
    own = _model(STARVING.replace("@Y@", "group own").replace("instance n : N {",
                                                                "instance n : N {\n    group own mutually_exclusive"))
    bound = analyze(own).task("n.Y").wcrt
    assert bound is not None
    worst = max(j.finish - j.release for j in simulate(own, Scenario(F(60, 1000))).finished("n.Y"))
    assert worst <= bound


def test_the_unbounded_callback_is_reported_with_the_remedy():
    from verify.core.diagnostics import DiagnosticSink
    from verify.timing.rta import check_response_times

    model = _model(STARVING.replace("@Y@", ""))
    analysis = analyze(model)
    sink = DiagnosticSink()
    check_response_times(model, {t.id: t.response for t in analysis.tasks}, sink)
    [diag] = [d for d in sink.items if d.code == "E312"]
    assert "`n.Y` on executor `e`" in diag.message and "callback group of its own" in diag.help


def test_a_reentrant_callback_runs_two_jobs_at_once_and_its_chains_have_no_bound():
    text = """
component N {
  out o : T
  task X { produces o wcet 5 ms bcet 5 ms }
}
component R {
  in i : T
  task Use { reads i wcet 1 ms bcet 1 ms }
}
system S {
  core c0
  core c1
  executor e multi_threaded on c0, c1 priority 5
  instance n : N {
    group r reentrant
    task X executor e group r timer 3 ms phase 0 ms
  }
  instance u : R { task Use executor e trigger i }
  connect n.o -> u.i
  chain c: n.o -> u.Use
}
"""
    model = _model(text)
    trace = simulate(model, Scenario(F(12, 1000)))
    x = _times(trace, "n.X")
    assert x[:2] == [(0, 0, 5), (3, 3, 8)]  # two jobs at once, on the two workers
    analysis = analyze(model)
    assert analysis.task("n.X").wcrt is not None
    chain = analysis.chain("c")
    assert chain.bound("reaction_time").worst is None
    assert "`n.X` may run two jobs at once" in chain.problem


def test_known_answers_of_the_multi_threaded_bound():
    """§9.4 by hand: x (3 ms) and y (1 ms) in groups of their own on two workers. For y: B = 1 ms
    (its previous job), carry-in 3 + 1 ms, x before y (two jobs): w = 1 + (4 + 2·3)/2 = 6 ms, R = 7 ms.
    For x: B = 3 ms, carry-in 4 ms, y after x (one job): w = 3 + (4 + 1)/2 = 5.5 ms, R = 8.5 ms."""
    model = _model(_two("group a", "group b", "group a mutually_exclusive group b mutually_exclusive"))
    analysis = analyze(model)
    assert analysis.task("n.Y").wcrt == 7 * MS
    assert analysis.task("n.X").wcrt == F(17, 2) * MS
    reentrant = analyze(_model(_two("group r", "group r", "group r reentrant")))
    # no blocking; y: carry 3 + 3 (x reentrant on both workers), x ahead once or twice: (6 + 2·3)/2 + 1
    assert reentrant.task("n.Y").wcrt == 7 * MS


@pytest.mark.parametrize("seed", range(40))
def test_the_integer_run_is_the_reference_run_on_multi_threaded_executors(seed):
    """``prove``'s integer simulator runs a multi-threaded executor's workers, its shared snapshot and
    its mutually exclusive groups job by job as ``verify.prove.sim`` does."""
    model = _model(mt_system(random.Random(seed)))
    rng = random.Random(seed)
    scenario = concrete_scenario(model, rng, F(rng.randrange(20, 400), 1000))
    trace = replay(model, scenario, 20_000)
    assert run_trace(model, scenario, 20_000) == trace
    targets = _targets(model)
    assert measure(model, scenario, targets, 20_000) == measure_reference(model, scenario, targets, 20_000)


@pytest.mark.parametrize("seed", range(40))
def test_no_simulated_latency_beyond_the_multi_threaded_bounds(seed):
    no_run_beyond_the_bounds(mt_system(random.Random(seed)), seed)


@pytest.mark.parametrize("seed", range(6))
def test_the_exact_search_on_multi_threaded_executors_lies_between_runs_and_the_bound(seed):
    model, text = rigid_system(mt_system, seed, 300)
    exact_between_runs_and_bound(model, text, random.Random(seed), 2)


LASER = """
component Laser { task Scan { wcet 2 ms } }
component Log { task Write { wcet 1 ms } }
system S {
  core c1
  core c2
  core c3
  @EXECUTORS@
  instance laser : Laser { task Scan @SCAN@ timer 25 ms }
  instance log : Log { task Write @WRITE@ timer 100 ms }
}
"""


def _codes(executors: str, scan: str = "executor e", write: str = "priority 1 on c3") -> list[tuple[str, int, int]]:
    text = LASER.replace("@EXECUTORS@", executors).replace("@SCAN@", scan).replace("@WRITE@", write)
    result = verify.load_text(text, "s.vfy")
    return [(d.code, d.span.line, d.span.column) for d in result.diagnostics]


@pytest.mark.parametrize("executors, scan, write, expected", [
    ("executor e multi_threaded 2 threads on c1, c2 priority 5", "executor e", "priority 1 on c3", []),
    ("executor e multi_threaded on c1, c2 priority 5", "executor e", "priority 1 on c3", []),
    # several cores or threads on a single-threaded executor
    ("executor e single_threaded on c1, c2 priority 5", "executor e", "priority 1 on c3", [("E224", 8, 37)]),
    ("executor e events 2 threads on c1 priority 5", "executor e", "priority 1 on c3", [("E224", 8, 21)]),
    # fewer threads than cores, a core listed twice
    ("executor e multi_threaded 1 thread on c1, c2 priority 5", "executor e", "priority 1 on c3",
     [("E224", 8, 29)]),
    ("executor e multi_threaded on c1, c1 priority 5", "executor e", "priority 1 on c3", [("E224", 8, 36)]),
    # a task or another executor on a multi-threaded executor's core
    ("executor e multi_threaded on c1, c2 priority 5", "executor e", "priority 1 on c2", [("E224", 10, 49)]),
    ("executor e multi_threaded on c1, c2 priority 5\n  executor f single_threaded on c2 priority 4",
     "executor e", "executor f", [("E224", 9, 33)]),
    # a group clause without an executor, an unknown group, an unknown group kind
    ("executor e multi_threaded on c1, c2 priority 5", "executor e", "priority 1 on c3 group g",
     [("E101", 10, 58)]),
])
def test_the_threads_and_groups_of_an_executor_are_checked(executors, scan, write, expected):
    assert _codes(executors, scan, write) == expected


def test_a_group_needs_an_executor_and_a_known_kind():
    text = LASER.replace("@EXECUTORS@", "executor e multi_threaded on c1, c2 priority 5")
    text = text.replace("instance log : Log {", "instance log : Log {\n    group g exclusive\n    group h reentrant\n")
    text = text.replace("@SCAN@", "executor e").replace("@WRITE@", "priority 1 on c3 group h")
    codes = [(d.code, d.message) for d in verify.load_text(text, "s.vfy").diagnostics]
    assert codes[0] == ("E108", "unknown callback-group kind `exclusive`")
    text = text.replace("group g exclusive", "group g mutually_exclusive")
    codes = [(d.code, d.message) for d in verify.load_text(text, "s.vfy").diagnostics]
    assert codes == [("E223", "task `log.Write` names callback group `h` but no executor")]


def test_groups_and_threads_keep_their_meaning_through_fmt():
    from verify.frontend.fmt import format_text

    text = _two("group r", "group r", "group r reentrant").replace("multi_threaded on", "multi_threaded 3 threads on")
    formatted, diags = format_text(text)
    assert diags == [] and formatted is not None
    assert "executor e multi_threaded 3 threads on c0, c1 priority 5" in formatted
    assert "    group r reentrant\n    task X executor e group r timer 10 ms phase 0 ms" in formatted
    before, after = _model(text), _model(formatted)
    assert [(t.id, t.group) for t in before.tasks] == [(t.id, t.group) for t in after.tasks]
    assert before.executors[0].workers == after.executors[0].workers == ("c0", "c1")
    assert before.executors[0].threads == 3 and before.groups == tuple(
        type(g)(g.id, g.instance, g.name, g.kind, g.executor, g.span) for g in before.groups)
    assert [(g.id, g.kind) for g in before.groups] == [("n.r", "reentrant")]


def _with_holes(seed: int) -> str:
    """A random multi-threaded system in which no callback can starve, whose unphased callback timers
    are period holes (at most two), with a reaction-time spec on its first chain."""
    from verify.synth.problem import starvation

    rng = random.Random(seed)
    holes = 0
    while not holes:
        text = mt_system(rng)
        if starvation(_model(text)) is not None:
            continue
        lines = []
        for line in text.splitlines():
            if "executor mt" in line and " timer " in line and " phase " not in line and holes < 2:
                head, tail = line.split(" timer ", 1)
                line = head + " timer ? in 10 ms .. 40 ms step 10 ms" + tail.split(" ms", 1)[1]
                holes += 1
            if line.startswith("  chain ch0:"):
                line += f" {{ reaction_time <= {rng.choice([60, 120, 240])} ms }}"
            lines.append(line)
    return "\n".join(lines) + "\n"


def test_synth_reports_a_callback_that_starves_in_every_configuration():
    """A callback behind another of its mutually exclusive group has no bound whatever the periods:
    ``synth`` says so at once (E401 naming it and the remedy) instead of trying configurations."""
    from verify.synth import synthesize

    text = STARVING.replace("@Y@", "").replace("timer 2 ms phase 1/2 ms", "timer ? in 2 ms .. 8 ms step 2 ms")
    result = synthesize(verify.load_text(text, "s.vfy"), objective="utilisation")
    assert result.status == "unsat" and result.stats["core_analyses"] <= 2
    [diag] = result.diagnostics
    assert diag.code == "E401" and "callback `n.Y` has no bound in any configuration (E312)" in diag.message
    assert "a callback group of its own" in diag.message


@pytest.mark.parametrize("seed", range(8))
def test_synth_on_multi_threaded_executors_agrees_with_brute_force(seed):
    from verify.synth import brute_force, synthesize

    from .test_synth import accepted, simulated_within_bounds

    text = _with_holes(seed)
    loaded = verify.load_text(text, "holes.vfy")
    assert loaded.ok, [(d.code, d.message) for d in loaded.diagnostics]
    result = synthesize(loaded, objective="utilisation")
    naive = brute_force(loaded, objective="utilisation")
    assert result.status == naive.status, text
    if result.status == "sat":
        assert result.optimal and result.values == naive.values, text
        assert accepted(result.model)
        simulated_within_bounds(result.model, runs=1, horizon=F(1))
