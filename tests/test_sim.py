"""Hand-computed timelines for the reference simulator (verify/prove/sim.py, specs/timing.md §1–§4)."""
from __future__ import annotations

import random
from fractions import Fraction as F

import pytest

from verify.model.system import (
    ChainModel, CoreModel, DataTriggered, HopModel, Periodic, ReadModel, SporadicSource, SystemModel, TaskModel
)
from verify.prove.sim import Scenario, ScenarioError, SimulationError, chain_latencies, random_scenario, simulate

from .builders import link

# ------------------------------------------------------------------ tiny model builders


def task(tid, act, *, prio=1, wcet=F(1, 10), bcet=None, core="c0", kind="preemptive", reads=(),
         produces=()):
    inst, name = tid.split(".")
    return TaskModel(id=tid, instance=inst, name=name, component=inst.upper(), kind=kind, core=core,
                     priority=prio, bcet=wcet if bcet is None else bcet, wcet=wcet,
                     reads=tuple(ReadModel(p, False, None, None) for p in reads),
                     produces=tuple(produces), activation=act)


def system(tasks, links=(), chain_tasks=()):
    """A system; ``chain_tasks`` lists task-id tuples, one chain each, hops found from the links."""
    chains = []
    for i, ids in enumerate(chain_tasks):
        hops = tuple(HopModel(a, b, next(lk for lk in links if lk.writer == a and b in lk.readers))
                     for a, b in zip(ids, ids[1:]))
        chains.append(ChainModel(f"ch{i}", tuple(ids), hops))
    cores = tuple(sorted({t.core for t in tasks}))
    return SystemModel("s", tuple(CoreModel(c) for c in cores), tuple(tasks), tuple(links), tuple(chains))


def timeline(trace, tid):
    return [(j.release, j.start, j.finish) for j in trace.jobs[tid]]


def releases(trace, tid):
    return [j.release for j in trace.jobs[tid]]


def source(tid, period, phase=F(0), core="c1", out="out", wcet=F(1, 10)):
    return task(tid, Periodic(F(period), F(phase)), core=core, produces=(out,), wcet=wcet)


# ------------------------------------------------------------------ §1 scheduling


def test_two_timers_preemption():
    hi = task("a.H", Periodic(F(5), F(1)), prio=2, wcet=F(2))
    lo = task("a.L", Periodic(F(10), F(0)), prio=1, wcet=F(4))
    tr = simulate(system([hi, lo]), Scenario(F(20)))
    assert timeline(tr, "a.L") == [(0, 0, 6), (10, 10, 16)]
    assert timeline(tr, "a.H") == [(1, 1, 3), (6, 6, 8), (11, 11, 13), (16, 16, 18)]


def test_equal_priority_fifo_then_task_order():
    a = task("x.A", Periodic(F(10), F(1)), wcet=F(2))
    b = task("x.B", Periodic(F(10), F(0)), wcet=F(2))
    c = task("x.C", Periodic(F(10), F(1)), wcet=F(2))
    tr = simulate(system([a, b, c]), Scenario(F(10)))
    assert [tr.job(t, 0).start for t in ("x.B", "x.A", "x.C")] == [0, 2, 4]


def test_cooperative_tasks_of_one_instance_never_overlap():
    p = task("x.P", Periodic(F(10), F(0)), core="c1", kind="cooperative", wcet=F(3))
    q = task("x.Q", Periodic(F(10), F(1)), core="c2", kind="cooperative", prio=5, wcet=F(3))
    r = task("y.R", Periodic(F(10), F(1)), core="c2", prio=0, wcet=F(1))  # runs while Q is blocked
    tr = simulate(system([p, q, r]), Scenario(F(10)))
    assert timeline(tr, "x.P") == [(0, 0, 3)]
    assert timeline(tr, "x.Q") == [(1, 3, 6)]
    assert timeline(tr, "y.R") == [(1, 1, 2)]


def test_cooperative_token_held_while_preempted():
    p = task("x.P", Periodic(F(10), F(0)), core="c1", kind="cooperative", prio=1, wcet=F(2))
    h = task("y.H", Periodic(F(10), F(1)), core="c1", prio=9, wcet=F(3))
    q = task("x.Q", Periodic(F(10), F(1)), core="c2", kind="cooperative", prio=1, wcet=F(1))
    tr = simulate(system([p, h, q]), Scenario(F(10)))
    assert timeline(tr, "x.P") == [(0, 0, 5)]  # 1 unit, preempted 1..4, 1 more
    assert timeline(tr, "x.Q") == [(1, 5, 6)]


def test_cooperative_random_runs_never_overlap():
    ts = [task(f"x.T{i}", SporadicSource(F(1), F(3)), core=f"c{i % 2}", kind="cooperative", prio=i,
               wcet=F(1, 2), bcet=F(0)) for i in range(4)]
    ts.append(task("y.H", Periodic(F(2)), core="c0", prio=9, wcet=F(1, 2), bcet=F(0)))
    sysm = system(ts)
    for seed in range(10):
        tr = simulate(sysm, random_scenario(sysm, random.Random(seed), F(30)))
        spans = sorted((j.start, j.finish) for t in ts[:4] for j in tr.finished(t.id))
        assert all(f1 <= s2 for (_, f1), (s2, _) in zip(spans, spans[1:]))
        for t in sysm.tasks:
            for j in tr.finished(t.id):
                assert j.release <= j.start <= j.finish - j.exec_time


# ------------------------------------------------------------------ §3 activation


def _trigger_system(act):
    a = source("a.Src", 1, out="out")
    b = source("b.Src", 3, out="out", core="c2")
    sink = task("s.Sink", act, core="c3", reads=("x", "y"))
    tasks = [a, b, sink]
    return system(tasks, [link("a.out", "s.x", tasks), link("b.out", "s.y", tasks)])


def test_prescaler_fires_every_third_arrival():
    sysm = _trigger_system(DataTriggered("x", ("x",), "single", 3))
    tr = simulate(sysm, Scenario(F(10)))
    assert releases(tr, "s.Sink") == [F(21, 10), F(51, 10), F(81, 10)]
    tr = simulate(sysm, Scenario(F(10), counter_phase={"s.Sink": 1}))
    assert releases(tr, "s.Sink") == [F(11, 10), F(41, 10), F(71, 10)]
    with pytest.raises(ScenarioError):
        simulate(sysm, Scenario(F(10), counter_phase={"s.Sink": 3}))


def test_and_compound_waits_for_both_members():
    a = source("a.Src", 2)
    b = source("b.Src", 3, core="c2")
    sink = task("s.Sink", DataTriggered("both", ("x", "y"), "and"), core="c3", reads=("x", "y"))
    tasks = [a, b, sink]
    sysm = system(tasks, [link("a.out", "s.x", tasks), link("b.out", "s.y", tasks)])
    tr = simulate(sysm, Scenario(F(10)))
    assert releases(tr, "s.Sink") == [F(1, 10), F(31, 10), F(61, 10), F(91, 10)]
    # the job released at 3.1 sees A's value from 2.1 and B's from 3.1
    j = tr.job("s.Sink", 1)
    assert (j.read("s.x").job, j.read("s.y").job) == (1, 1)


def test_or_compound_fires_on_either():
    a = source("a.Src", 2)
    b = source("b.Src", 3, core="c2")
    sink = task("s.Sink", DataTriggered("any", ("x", "y"), "or"), core="c3", reads=("x", "y"), wcet=F(0))
    tasks = [a, b, sink]
    sysm = system(tasks, [link("a.out", "s.x", tasks), link("b.out", "s.y", tasks)])
    tr = simulate(sysm, Scenario(F(10)))
    expect = [F(n, 10) for n in (1, 1, 21, 31, 41, 61, 61, 81, 91)]
    assert releases(tr, "s.Sink") == expect
    assert all(j.finish == j.release for j in tr.jobs["s.Sink"])


def test_sporadic_releases_follow_interarrivals():
    t = task("a.S", SporadicSource(F(1), F(2)), wcet=F(0))
    gaps = [F(1), F(2), F(3, 2)]
    sc = Scenario(F(6), phases={"a.S": F(1, 2)}, interarrival=lambda tid, i: gaps[i % 3])
    assert releases(simulate(system([t]), sc), "a.S") == [F(1, 2), F(3, 2), F(7, 2), 5]
    with pytest.raises(ScenarioError):
        simulate(system([t]), Scenario(F(6), interarrival=lambda tid, i: F(3)))


# ------------------------------------------------------------------ §2 communication


def test_connection_delay_shifts_arrivals_and_stays_fifo():
    src = source("a.Src", F(1, 2))
    rd = task("b.R", Periodic(F(10)), core="c2", reads=("in",))
    tasks = [src, rd]
    sysm = system(tasks, [link("a.out", "b.in", tasks, F(1, 4), F(1))])
    delays = [F(1), F(1, 4), F(1, 4)]
    tr = simulate(sysm, Scenario(F(3, 2), delay=lambda s, t, i: delays[i]))
    # written at 0.1, 0.6, 1.1: 0.1+1 = 1.1; 0.6+0.25 = 0.85 -> held back to 1.1 (FIFO); 1.35
    assert [(m.index, m.written, m.arrival) for m in tr.messages] == [
        (0, F(1, 10), F(11, 10)), (1, F(6, 10), F(11, 10)), (2, F(11, 10), F(135, 100))]
    with pytest.raises(ScenarioError):
        simulate(sysm, Scenario(F(2), delay=lambda s, t, i: F(2)))


def test_register_reader_sees_latest_value_or_none():
    src = source("a.Src", 1)
    rd = task("b.R", Periodic(F(3)), core="c2", reads=("in",))
    tasks = [src, rd]
    sysm = system(tasks, [link("a.out", "b.in", tasks)])
    tr = simulate(sysm, Scenario(F(7), phases={"b.R": F(0)}))
    assert tr.job("b.R", 0).read("b.in") is None  # nothing arrived at 0
    assert tr.job("b.R", 1).read("b.in").job == 2  # at 3: written 2.1 (3.1 not yet)
    tr = simulate(sysm, Scenario(F(7), phases={"b.R": F(1, 10)}))
    assert [tr.job("b.R", i).read("b.in").job for i in range(3)] == [0, 3, 6]  # arrivals at 0.1, ...


# ------------------------------------------------------------------ §4 chains


def _two_task_chain():
    src = task("a.Src", Periodic(F(2), F(0)), core="c1", wcet=F(1, 2), produces=("out",))
    snk = task("b.Snk", Periodic(F(3), F(1)), core="c2", wcet=F(1, 2), reads=("in",))
    tasks = [src, snk]
    return system(tasks, [link("a.out", "b.in", tasks)], [("a.Src", "b.Snk")])


def test_two_task_chain_latencies_by_hand():
    sysm = _two_task_chain()
    lat = chain_latencies(simulate(sysm, Scenario(F(12))), sysm.chains[0])
    # Src reads at 0,2,4,6,8,10 and writes at +0.5; Snk runs 1,4,7,10 (+0.5), sees stamps 0,2,6,8
    assert [s.value for s in lat.data_age] == [F(3, 2), F(5, 2), F(3, 2), F(5, 2)]
    assert [s.value for s in lat.data_age_nonreduced] == [F(9, 2), F(7, 2), F(9, 2)]
    assert [s.value for s in lat.reaction_time] == [F(9, 2), F(11, 2), F(7, 2), F(9, 2)]
    assert [s.value for s in lat.reaction_time_reduced] == [F(5, 2), F(7, 2), F(3, 2), F(5, 2)]
    worst = lat.worst("reaction_time")
    assert (worst.value, worst.origin, worst.stamp, worst.last) == (F(11, 2), 1, 3, 2)
    assert (lat.worst().value, lat.best().value) == (F(5, 2), F(3, 2))
    assert lat.best("reaction_time").value == F(7, 2)
    assert "a.Src#1" in worst.explain(sysm.chains[0])


def test_three_task_chain_carries_stamp_through_trigger():
    src = task("a.Src", Periodic(F(2), F(0)), core="c1", wcet=F(1, 2), produces=("out",))
    mid = task("m.Mid", DataTriggered("in", ("in",)), core="c2", wcet=F(1, 4), reads=("in",),
               produces=("out",))
    snk = task("b.Snk", Periodic(F(3), F(1)), core="c3", wcet=F(1, 2), reads=("in",))
    tasks = [src, mid, snk]
    links = [link("a.out", "m.in", tasks), link("m.out", "b.in", tasks, F(1, 4))]
    sysm = system(tasks, links, [("a.Src", "m.Mid", "b.Snk")])
    lat = chain_latencies(simulate(sysm, Scenario(F(12))), sysm.chains[0])
    # Mid finishes at 0.75, 2.75, ...; arrivals at Snk at 1, 3, 5, 7, 9; Snk reads at 1,4,7,10
    assert [(s.stamp, s.value) for s in lat.data_age] == [(0, F(3, 2)), (1, F(5, 2)), (3, F(3, 2)),
                                                         (4, F(5, 2))]


def test_chain_ignores_jobs_after_horizon():
    sysm = _two_task_chain()
    lat = chain_latencies(simulate(sysm, Scenario(F(21, 2))), sysm.chains[0])
    assert len(lat.data_age) == 3  # Snk's job at 10 finishes at 10.5 = horizon: not counted


# ------------------------------------------------------------------ scenarios and determinism


def _mixed_system():
    src = task("a.Src", Periodic(F(2)), core="c1", wcet=F(1, 2), bcet=F(1, 10), produces=("out",))
    sp = task("a.Sp", SporadicSource(F(1), F(4)), core="c1", prio=3, wcet=F(1, 4), bcet=F(0),
              produces=("ev",))
    mid = task("m.Mid", DataTriggered("in", ("in",), "single", 2), core="c2", kind="cooperative",
               wcet=F(1, 4), bcet=F(0), reads=("in",), produces=("out",))
    mix = task("m.Mix", DataTriggered("any", ("in", "ev"), "or"), core="c2", kind="cooperative",
               prio=2, wcet=F(1, 4), bcet=F(1, 8), reads=("in", "ev"))
    snk = task("b.Snk", Periodic(F(3)), core="c2", wcet=F(1, 2), bcet=F(1, 4), reads=("in",))
    tasks = [src, sp, mid, mix, snk]
    links = [link("a.out", "m.in", tasks, F(0), F(1, 2)), link("a.ev", "m.ev", tasks),
             link("m.out", "b.in", tasks, F(1, 10), F(3, 10))]
    return system(tasks, links, [("a.Src", "m.Mid", "b.Snk")])


def test_random_scenarios_are_legal_and_deterministic():
    sysm = _mixed_system()
    for seed in range(5):
        sc = random_scenario(sysm, random.Random(seed), F(40))
        assert sc == random_scenario(sysm, random.Random(seed), F(40))
        t1, t2 = simulate(sysm, sc), simulate(sysm, sc)
        assert t1 == t2
        assert sc.exec_time("a.Src", 7) == sc.exec_time("a.Src", 7)
        lat = chain_latencies(t1, sysm.chains[0])
        assert lat.data_age and lat.reaction_time
        assert all(s.value >= 0 for k in ("data_age", "reaction_time") for s in getattr(lat, k))


def test_random_scenarios_hit_the_extremes():
    sysm = _mixed_system()
    sc = random_scenario(sysm, random.Random(1), F(40))
    execs = {sc.exec_time("a.Src", i) for i in range(200)}
    assert {F(1, 10), F(1, 2)} <= execs and all(F(1, 10) <= c <= F(1, 2) for c in execs)
    delays = {sc.delay("m.out", "b.in", i) for i in range(200)}
    assert {F(1, 10), F(3, 10)} <= delays


def test_illegal_choices_are_rejected():
    sysm = _two_task_chain()
    with pytest.raises(ScenarioError):
        simulate(sysm, Scenario(F(10), exec_time=lambda t, i: F(1)))
    with pytest.raises(ScenarioError):
        simulate(sysm, Scenario(F(10), phases={"a.Src": F(1)}))  # phase fixed to 0 by the model


def test_zero_time_loop_hits_event_cap():
    kick = source("k.Kick", 10)
    a = task("a.A", DataTriggered("any", ("x", "y"), "or"), wcet=F(0), core="c2", reads=("x", "y"),
             produces=("out",))
    b = task("b.B", DataTriggered("in", ("in",)), wcet=F(0), core="c3", reads=("in",), produces=("out",))
    tasks = [kick, a, b]
    links = [link("k.out", "a.x", tasks), link("b.out", "a.y", tasks), link("a.out", "b.in", tasks)]
    with pytest.raises(SimulationError):
        simulate(system(tasks, links), Scenario(F(1)), max_events=10_000)
