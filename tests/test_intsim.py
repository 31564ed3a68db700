"""The integer simulator of ``verify/prove/intsim.py`` against the reference simulator ``verify.prove.sim``:
the same jobs, reads and samples for every kind of concrete scenario the searches of ``prove`` draw
(phases, counter phases, per-job patterns of execution times, delays and inter-arrival times), and
the same errors for choices outside their ranges."""
from __future__ import annotations

import random
from fractions import Fraction as F

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.model.system import DataTriggered, Periodic, SporadicSource
from verify.prove import Target
from verify.prove.intsim import run_trace, target_samples
from verify.prove.measure import measure
from verify.prove.scenario import (ConcreteScenario, _chain_samples, _response_samples, extremes, measure_reference,
                                   replay)
from verify.prove.sim import ScenarioError, SimulationError, pick_in

from .test_bounds_vs_simulation import systems
from .test_prove import KINDS
from .test_timing import MS, chain, link, system, task, timer


def _pattern(rng: random.Random, lo: F, hi: F) -> tuple[F, ...]:
    return tuple(pick_in(rng, lo, hi) for _ in range(rng.randrange(1, 5)))


def concrete_scenario(model, rng: random.Random, horizon: F) -> ConcreteScenario:
    """Every free choice of ``model`` drawn within its range; each kind of pattern only sometimes."""
    phases, counters, execs, delays, gaps = [], [], [], [], []
    for t in model.tasks:
        act = t.activation
        if isinstance(act, Periodic) and act.phase is None and rng.random() < 0.8:
            phases.append((t.id, act.period * F(rng.randrange(12), 12)))
        elif isinstance(act, SporadicSource):
            if rng.random() < 0.8:
                phases.append((t.id, act.max_interarrival * F(rng.randrange(12), 12)))
            if rng.random() < 0.7:
                gaps.append((t.id, _pattern(rng, act.min_interarrival, act.max_interarrival)))
        elif isinstance(act, DataTriggered) and act.prescaler > 1:
            counters.append((t.id, rng.randrange(act.prescaler)))
        if t.bcet != t.wcet and rng.random() < 0.7:
            execs.append((t.id, _pattern(rng, t.bcet, t.wcet)))
    for lk in model.links:
        if lk.delay_min != lk.delay_max and rng.random() < 0.7:
            delays.append(((lk.source, lk.target), _pattern(rng, lk.delay_min, lk.delay_max)))
    return ConcreteScenario(horizon, tuple(phases), tuple(counters), tuple(execs), tuple(delays), tuple(gaps))


def _targets(model) -> list[Target]:
    return [Target(k, c.name) for c in model.chains for k in KINDS] + [Target("response", t.id) for t in model.tasks]


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(systems(), st.integers(0, 2**16))
def test_the_integer_run_is_the_reference_run(text, seed):
    """Random systems (sporadic sources, AND/OR compounds, prescalers, cooperative siblings,
    execution-time and delay ranges) and random concrete scenarios: the whole trace (every job with
    what it read, every message), every sample of every target and every extreme agree with
    ``verify.prove.sim``, or both refuse the run alike."""
    model = verify.load_text(text, "random.vfy").system()
    rng = random.Random(seed)
    scenario = concrete_scenario(model, rng, F(rng.randrange(20, 400), 1000))
    try:
        trace = replay(model, scenario, 20_000)
    except (ScenarioError, SimulationError) as err:
        with pytest.raises(type(err)) as fast:
            measure(model, scenario, _targets(model), 20_000)
        assert str(fast.value).split(" by t=")[0] == str(err).split(" by t=")[0]
        assert getattr(fast.value, "at", None) == getattr(err, "at", None)
        return
    assert run_trace(model, scenario, 20_000) == trace, text
    some = [tk.id for tk in model.tasks if rng.random() < 0.5]
    part = run_trace(model, scenario, 20_000, tasks=some)
    assert part.jobs == {tid: trace.jobs[tid] for tid in some}, text
    read = {m for tid in some for j in trace.jobs[tid] for _port, m in j.reads if m is not None}
    assert part.messages == tuple(m for m in trace.messages if m in read), text
    targets = _targets(model)
    assert target_samples(model, scenario, targets, 20_000) == {
        t: _response_samples(trace, t, with_open=True) if t.kind == "response"
        else list(_chain_samples(trace, model, t)) for t in targets}, text
    assert measure(model, scenario, targets, 20_000) == measure_reference(model, scenario, targets, 20_000), text
    cut = measure(model, scenario, targets, 20_000, event_budget=rng.randrange(1, 300))
    assert cut == measure_reference(model, cut.scenario, targets, 20_000), text


def _pair():
    ts = [task("a.A", timer(4), wcet=2 * MS, bcet=MS, prio=2, produces=["o"]),
          task("b.B", SporadicSource(3 * MS, 6 * MS), wcet=MS, prio=1, reads=["i"], produces=["o"])]
    ls = [link("a.o", "b.i", ts, MS, 2 * MS)]
    return system(ts, ls, [chain("ch", ["a.A", "b.B"], ls)])


@pytest.mark.parametrize("change, message", [
    ({"exec_times": (("a.A", (2 * MS, 3 * MS)),)}, "a.A#1: execution time 3/1000 outside [1/1000, 1/500]"),
    ({"delays": ((("a.o", "b.i"), (MS, MS / 2)),)}, "a.o->b.i#1: delay 1/2000 outside [1/1000, 1/500]"),
    ({"interarrivals": (("b.B", (4 * MS, 7 * MS)),)}, "b.B#1: inter-arrival 7/1000 outside [3/1000, 3/500]"),
    ({"phases": (("b.B", 6 * MS),)}, "b.B: first release 3/500 outside [0, 3/500)"),
    ({"phases": (("a.A", 4 * MS),)}, "a.A: phase 1/250 outside [0, 1/250)"),
])
def test_a_choice_outside_its_range_is_refused_as_the_reference_refuses_it(change, message):
    """A pattern entry outside its range is refused when the run first uses it (here the second job,
    message or release), with the reference simulator's message."""
    model = _pair()
    scenario = ConcreteScenario(horizon=F(30, 1000), **change)
    with pytest.raises(ScenarioError) as ref:
        replay(model, scenario)
    with pytest.raises(ScenarioError) as fast:
        measure(model, scenario, [Target("data_age", "ch")])
    assert str(fast.value) == str(ref.value) == message


def test_an_illegal_entry_the_run_never_uses_is_not_refused():
    """Like the reference, which checks each choice when it is made: a pattern longer than the run
    may hold an entry out of range at a position no job reaches."""
    model = _pair()
    scenario = ConcreteScenario(horizon=F(3, 1000), exec_times=(("a.A", (2 * MS, 9 * MS)),))
    assert measure(model, scenario, [Target("response", "a.A")]) == \
        measure_reference(model, scenario, [Target("response", "a.A")])


def test_many_pending_jobs_on_one_core():
    """The heap of ready jobs: 60 timers released together on one core, and a cooperative pair: at
    1 ms the better-ranked sibling sits on top of the heap but must wait for the token, so the core
    runs the sibling that holds it. As in the reference."""
    ts = [task(f"t{i}.T", timer(10 + i % 3), wcet=MS / 10, prio=i % 7, core="c0") for i in range(60)]
    ts += [task("k.X", timer(10), wcet=3 * MS, prio=10, core="c0", kind="cooperative"),
           task("k.Y", timer(10, 1), wcet=MS, prio=50, core="c0", kind="cooperative")]
    model = system(ts, [], [])
    scenario = ConcreteScenario(horizon=F(40, 1000))
    targets = [Target("response", t.id) for t in model.tasks]
    assert measure(model, scenario, targets) == measure_reference(model, scenario, targets)


def test_the_event_cap_stops_both_simulators_at_the_same_instant():
    model = _pair()
    scenario = ConcreteScenario(horizon=F(1))
    with pytest.raises(SimulationError) as ref:
        replay(model, scenario, 50)
    with pytest.raises(SimulationError) as fast:
        measure(model, scenario, [Target("data_age", "ch")], 50)
    assert fast.value.at == ref.value.at and 0 < ref.value.at < 1
    shorter = scenario.with_horizon(ref.value.at)  # every event before the cap's instant fits
    assert measure(model, shorter, [Target("data_age", "ch")], 50) == \
        measure_reference(model, shorter, [Target("data_age", "ch")], 50)


def test_an_event_budget_ends_the_run_at_an_instant():
    """``measure`` with an event budget: the run ends at the first instant reached with that many
    events processed, before any event of it, and is the reference run with that horizon."""
    model = _pair()
    targets = [Target("data_age", "ch"), Target("response", "a.A"), Target("response", "b.B")]
    m = measure(model, ConcreteScenario(horizon=F(1)), targets, event_budget=50)
    assert 0 < m.horizon < 1 and m.scenario.horizon == m.horizon
    assert m == measure_reference(model, m.scenario, targets)
    assert m.horizon > measure(model, ConcreteScenario(horizon=F(1)), targets, event_budget=40).horizon


def test_a_search_run_past_its_event_budget_counts_up_to_where_it_stopped():
    """A falsifying search run with more events than its budget is measured over the prefix the
    budget allows (a shorter run, hence a real one) instead of being thrown away."""
    from verify.prove.exact import Budget, Goal, search

    model = _pair()
    found = search(model, [Goal(Target("data_age", "ch"), above=F(1))], Budget(3), F(1), max_events=50)
    assert found.explored == 3
    run = found.worst[Target("data_age", "ch")]
    assert run.horizon < 1 and run.scenario.horizon == run.horizon
    trace = replay(model, run.scenario)  # the shorter run replays in the reference simulator
    assert extremes(trace, model, Target("data_age", "ch")).worst == run.values[Target("data_age", "ch")].worst
