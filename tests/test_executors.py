"""ROS 2 executors (specs/timing.md §9): the job-level semantics of the reference simulator on known
runs, the response-time bounds of callbacks on known answers, and property tests — every bound against
the simulator, the integer simulator of ``prove`` against the reference, and the exact search of
``prove`` against the bound and against runs off its grid — on random systems with executors."""
from __future__ import annotations

import random
from fractions import Fraction as F

import pytest

import verify
from verify.prove import Target
from verify.prove.exact import Budget, count_representatives, enumerate_exact, exact_class, grid_of, scenario_of
from verify.prove.measure import measure, measure_periodic
from verify.prove.scenario import measure_periodic_reference, measure_reference, replay
from verify.prove.intsim import run_trace
from verify.prove.sim import Scenario, random_scenario, simulate
from verify.timing import analyze

from .executor_systems import executor_system, mt_system
from .test_intsim import _targets, concrete_scenario
from .test_prove import KINDS as PROVE_KINDS
from .test_timing import MS, bound_violations

SENSOR = """
component Timer { out o : T  task Run { produces o wcet @C@ bcet @C@ } }
component Sub { in i : T  out o : T  task Run { reads i produces o wcet @C@ bcet @C@ } }
"""


def _model(text: str):
    result = verify.load_text(text, "ex.vfy")
    assert result.ok, [(d.code, d.message) for d in result.diagnostics]
    return result.system()


def _times(trace, task):
    """(release, start, finish) of every job of ``task``, in ms."""
    return [(j.release / MS, j.start / MS if j.start is not None else None,
             j.finish / MS if j.finish is not None else None) for j in trace.jobs[task]]


def _three(kind: str) -> str:
    """A busy callback ``a`` (timer at 0, 2 ms), a subscription ``s`` (a sporadic source) declared
    before a timer ``b`` (released at 1/2 ms), one executor of ``kind``."""
    return f"""
component A {{ task Run {{ wcet 2 ms bcet 2 ms }} }}
component B {{ task Run {{ wcet 1 ms bcet 1 ms }} }}
system S {{
  core c
  executor e {kind} on c priority 5
  instance a : A {{ task Run executor e timer 100 ms phase 0 ms }}
  instance s : B {{ task Run executor e sporadic 100 ms .. 200 ms }}
  instance b : B {{ task Run executor e timer 100 ms phase 1/2 ms }}
}}
"""


@pytest.mark.parametrize("kind, first", [("single_threaded", "b.Run"), ("static_single_threaded", "s.Run"),
                                         ("events", "b.Run")])
def test_the_order_of_a_snapshot_is_the_executors(kind, first):
    """At the polling point after ``a`` (2 ms) both are pending: rclcpp's SingleThreadedExecutor takes
    timers first, the static executor subscriptions first, the events executor the earlier event."""
    model = _model(_three(kind))
    trace = simulate(model, Scenario(F(20, 1000), phases={"s.Run": MS}))
    assert _times(trace, "a.Run") == [(0, 0, 2)]
    second = "s.Run" if first == "b.Run" else "b.Run"
    assert _times(trace, first)[0][1:] == (2, 3)
    assert _times(trace, second)[0][1:] == (3, 4)


def test_a_message_arriving_during_a_round_waits_for_the_next_polling_point():
    """`filter` is triggered at 2 ms while the snapshot of 0 ms still holds `log`: it runs after it,
    although it is ready before `log` starts."""
    text = SENSOR.replace("@C@", "2 ms") + """
component Log { task Run { wcet 4 ms bcet 4 ms } }
system S {
  core c
  executor e single_threaded on c priority 5
  instance sensor : Timer { task Run executor e timer 10 ms }
  instance filter : Sub { task Run executor e trigger i }
  instance log : Log { task Run executor e timer 20 ms }
  connect sensor.o -> filter.i
}
"""
    trace = simulate(_model(text), Scenario(F(30, 1000)))
    assert _times(trace, "sensor.Run")[:2] == [(0, 0, 2), (10, 10, 12)]
    assert _times(trace, "log.Run")[0] == (0, 2, 6)
    assert _times(trace, "filter.Run")[:2] == [(2, 6, 8), (12, 12, 14)]


@pytest.mark.parametrize("kind", ["single_threaded", "events"])
def test_a_pending_timer_absorbs_its_next_releases_except_on_the_events_executor(kind):
    """rcl's timer skips the periods missed while its callback waits; the events executor queues one
    event per expiry."""
    text = f"""
component Long {{ task Run {{ wcet 25 ms bcet 25 ms }} }}
component Short {{ task Run {{ wcet 1 ms bcet 1 ms }} }}
system S {{
  core c
  executor e {kind} on c priority 5
  instance long : Long {{ task Run executor e timer 100 ms phase 0 ms }}
  instance tick : Short {{ task Run executor e timer 10 ms phase 1 ms }}
}}
"""
    trace = simulate(_model(text), Scenario(F(40, 1000)))
    if kind == "events":
        assert _times(trace, "tick.Run") == [(1, 25, 26), (11, 26, 27), (21, 27, 28), (31, 31, 32)]
    else:
        assert _times(trace, "tick.Run") == [(1, 25, 26), (31, 31, 32)]


def test_an_executor_thread_is_preempted_by_higher_threads_and_preempts_lower_ones():
    text = """
component W { task Run { wcet 5 ms bcet 5 ms } }
component H { task Run { wcet 2 ms bcet 2 ms } }
system S {
  core c
  executor e single_threaded on c priority 5
  instance cb : W { task Run executor e timer 100 ms phase 0 ms }
  instance high : H on c { task Run priority 9 timer 100 ms phase 1 ms }
  instance low : H on c { task Run priority 1 timer 100 ms phase 0 ms }
}
"""
    trace = simulate(_model(text), Scenario(F(20, 1000)))
    assert _times(trace, "cb.Run") == [(0, 0, 7)]
    assert _times(trace, "high.Run") == [(1, 1, 3)]
    assert _times(trace, "low.Run") == [(0, 7, 9)]


def _bursty(kind: str = "single_threaded") -> str:
    """``a`` is triggered by `p` on another core, whose response jitter (14 ms) exceeds its period:
    a's activations come in bursts."""
    return f"""
component P {{ out o : T  task Run {{ produces o wcet 4 ms }} }}
component H {{ task Run {{ wcet 10 ms }} }}
component A {{ in i : T  task Run {{ reads i wcet 3 ms }} }}
component B {{ task Run {{ wcet 1/2 ms }} }}
system S {{
  core c
  core d
  executor e {kind} on c priority 5
  instance p : P on d {{ task Run priority 1 timer 10 ms }}
  instance h : H on d {{ task Run priority 2 timer 20 ms }}
  instance a : A {{ task Run executor e trigger i }}
  instance b : B {{ task Run executor e timer 100 ms }}
  instance i : B {{ task Run executor e sporadic 50 ms .. 60 ms }}
  connect p.o -> a.i
}}
"""


def test_known_answers_of_the_callback_bounds():
    """Casini et al.'s Eq. (6) for ``i`` (offset 0): ``F = 1/2 + η̄ₐ(F − 1/2)·3 + η̄_b(F − 1/2)·1/2`` with
    ``η̄ₐ(Δ) = ⌊(Δ + 14)/10⌋ + 1``: 7, then 10, a fixed point; the polling rounds give
    ``1/2 + (3 + 1/2 + 1/2) + (3 + 1/2) = 8``, the bound. On the events executor ``i`` waits for what is
    queued at its release: ``η̄ₐ(0)·3 + 1/2 + 1/2 = 7``."""
    analysis = analyze(_model(_bursty()))
    assert analysis.task("p.Run").wcrt == 14 * MS
    r = analysis.task("i.Run").response
    assert (r.wcrt, r.rule) == (8 * MS, "single_threaded executor, polling rounds")
    assert r.hold == MS / 2
    events = analyze(_model(_bursty("events"))).task("i.Run").response
    assert (events.wcrt, events.rule) == (7 * MS, "events executor, FIFO busy window, 1 offset")


def test_the_busy_window_bound_of_eq6_is_reached_by_a_run():
    """a (timer 4 ms, 2 ms), b (timer 100 ms, 2 ms), i (sporadic, 1 ms): Eq. (6) gives 7 ms for i; the
    run with i released 1/2 ms after the polling point of a and b takes 6 1/2 ms (a runs twice before
    it: once in the round in progress, once in the next, ordered first)."""
    text = """
component A { task Run { wcet 2 ms bcet 2 ms } }
component I { task Run { wcet 1 ms bcet 1 ms } }
system S {
  core c
  executor e single_threaded on c priority 5
  instance a : A { task Run executor e timer 4 ms phase 0 ms }
  instance b : A { task Run executor e timer 100 ms phase 0 ms }
  instance i : I { task Run executor e sporadic 20 ms .. 40 ms }
}
"""
    model = _model(text)
    assert analyze(model).task("i.Run").wcrt == 7 * MS
    trace = simulate(model, Scenario(F(10, 1000), phases={"i.Run": MS / 2}))
    assert _times(trace, "i.Run")[0] == (F(1, 2), 6, 7)


@pytest.mark.parametrize("seed", range(40))
def test_no_simulated_latency_beyond_the_bounds(seed):
    """Random systems with executors of every kind: no run exceeds a response-time or chain bound."""
    no_run_beyond_the_bounds(executor_system(random.Random(seed)), seed)


def no_run_beyond_the_bounds(text: str, seed: int, transform=lambda model: model) -> None:
    """Three runs of 1 s of the system ``text`` (``transform``ed: the first with every job at its wcet and
    every message at its least delay) stay within its bounds."""
    model = transform(_model(text))
    analysis = analyze(model)
    for run in range(3):
        scenario = random_scenario(model, random.Random(f"{seed}/{run}"), F(1))
        if run == 0:
            scenario = Scenario(scenario.horizon, scenario.phases, None, None, None, scenario.counter_phase)
        assert bound_violations(model, simulate(model, scenario), analysis) == [], text


@pytest.mark.parametrize("seed", range(40))
def test_the_integer_run_is_the_reference_run(seed):
    """``prove``'s integer simulator runs executors job by job as ``verify.prove.sim`` does: the same trace
    and the same samples of every target."""
    model = _model(executor_system(random.Random(seed)))
    rng = random.Random(seed)
    scenario = concrete_scenario(model, rng, F(rng.randrange(20, 400), 1000))
    trace = replay(model, scenario, 20_000)
    assert run_trace(model, scenario, 20_000) == trace
    targets = _targets(model)
    assert measure(model, scenario, targets, 20_000) == measure_reference(model, scenario, targets, 20_000)


def rigid_system(generate, seed: int, limit: int):
    """The first random system of ``generate`` from ``seed`` in the exact class whose enumeration has at
    most ``limit`` representatives."""
    rng = random.Random(seed)
    while True:
        text = generate(rng, rigid=True)
        model = _model(text)
        if exact_class(model) is None and count_representatives(grid_of(model), limit) <= limit:
            return model, text


@pytest.mark.parametrize("seed", range(8))
def test_the_exact_search_lies_between_runs_and_the_bound(seed):
    """The exact supremum of ``prove`` (proof spec §4.4) on rigid systems with executors is at most
    the analysis' bound and at least every run at random phases off the grid; the periodic evaluation
    (the timing state holds each executor's snapshot) agrees with the reference simulator's."""
    model, text = rigid_system(executor_system, seed, 400)
    exact_between_runs_and_bound(model, text, random.Random(seed), 3)


def exact_between_runs_and_bound(model, text: str, rng: random.Random, count: int) -> None:
    """The exact supremum of every chain and callback response target of ``model`` is at most the
    analysis' bound and at least each of ``count`` runs at random phases off the grid, whose periodic
    evaluation agrees with the reference simulator's."""
    targets = [Target(k, c.name) for c in model.chains for k in PROVE_KINDS]
    targets += [Target("response", t.id) for t in model.tasks if t.executor is not None]
    exact = enumerate_exact(model, targets, Budget(5000))
    assert exact is not None and exact.complete, text
    analysis = analyze(model)
    grid = grid_of(model)
    runs = []
    for _ in range(count):
        phases = {a: F(rng.randrange(p * 97), 97) * grid.tick for a, p in zip(grid.timers, grid.periods)}
        scenario = scenario_of(phases, {})
        runs.append(measure_periodic(model, scenario, targets, grid.hyper))
        assert runs[-1] == measure_periodic_reference(model, scenario, targets, grid.hyper), text
    for t in targets:
        value = exact.worst[t].value
        if value is None:
            continue
        bound = (analysis.task(t.name).wcrt if t.kind == "response"
                 else analysis.chain(t.name).bound(t.kind).worst)
        assert bound is None or value <= bound, (t, value, bound, text)
        for m in runs:
            s = m.values[t].worst if m.complete else None
            assert s is None or s.value <= value, (t, s.value, value, text)


def _with_holes(seed: int) -> str:
    """A random executor system whose callbacks' unphased timers are period holes (at most two), with a
    reaction-time spec on its first chain."""
    rng = random.Random(seed)
    holes = 0
    while not holes:
        text = executor_system(rng)
        lines = []
        for line in text.splitlines():
            if "executor e" in line and " timer " in line and " phase " not in line and holes < 2:
                head, tail = line.split(" timer ", 1)
                line = head + " timer ? in 10 ms .. 40 ms step 10 ms " + tail.split(" ", 2)[2]
                holes += 1
            if line.startswith("  chain ch0:"):
                line += f" {{ reaction_time <= {rng.choice([30, 60, 120])} ms }}"
            lines.append(line)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("seed", range(12))
def test_synth_on_executors_agrees_with_brute_force(seed):
    """Period holes on callbacks' timers: ``synth`` finds what enumerating every candidate finds (the
    same status, the same optimal choices), and its configuration passes the analysis and the
    simulator."""
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


@pytest.mark.parametrize("seed", range(20))
def test_what_an_executors_callbacks_share_is_built_once_without_changing_a_bound(seed):
    """``executor_responses`` builds each executor's streams, time base and busy window once for all its
    callbacks; every response is the one ``callback_response`` computes for the callback alone."""
    from verify.timing.executors import callback_response, executor_responses

    rng = random.Random(seed)
    model = _model(executor_system(rng) if seed % 2 else mt_system(rng))
    analysis = analyze(model)
    events = {t.id: t.events for t in analysis.tasks}
    estimates = {t.id: t.wcrt for t in analysis.tasks}
    shared = executor_responses(model, events, estimates)
    assert list(shared) == [t.id for t in model.tasks if t.executor is not None]
    for t in model.tasks:
        if t.executor is not None:
            assert shared[t.id] == callback_response(model, t, events, estimates)
