"""Cones (specs/proof.md §4.0): an obligation depends only on its cone, so ``prove`` searches the
cone's subsystem. Checked against the reference simulator on random systems, against exact
enumeration of the whole system, and on known cases that only the cone makes decidable."""
from __future__ import annotations

import random
from fractions import Fraction as F

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.prove import Target, prove, replay
from verify.prove.cone import cone, restrict
from verify.prove.exact import Budget, enumerate_exact, exact_class
from verify.prove.sim import Scenario, chain_latencies, random_scenario, simulate

from .test_bounds_vs_simulation import systems
from .test_prove import KINDS, rigid_systems
from .test_timing import MS, chain, link, system, task, timer, trigger


def _timing(trace, tasks):
    """Every job of ``tasks`` without what it read (values from outside the cone may differ)."""
    return {tid: [(j.index, j.release, j.exec_time, j.start, j.finish) for j in trace.jobs[tid]] for tid in tasks}


def _mixed(inside: Scenario, outside: Scenario, tasks: frozenset[str], model) -> Scenario:
    """The choices of ``inside`` for the cone's tasks and connections, those of ``outside`` elsewhere."""
    writer = {(lk.source, lk.target): lk.writer for lk in model.links}

    def exec_time(tid, i):
        return (inside if tid in tasks else outside).exec_time(tid, i)

    def delay(src, dst, i):
        return (inside if writer[(src, dst)] in tasks else outside).delay(src, dst, i)

    def gap(tid, i):
        return (inside if tid in tasks else outside).interarrival(tid, i)

    pick = {**outside.phases, **{t: p for t, p in inside.phases.items() if t in tasks}}
    counters = {**outside.counter_phase, **{t: c for t, c in inside.counter_phase.items() if t in tasks}}
    return Scenario(inside.horizon, pick, exec_time, delay, gap, counters)


@pytest.mark.slow
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(systems(), st.integers(0, 2**16))
def test_a_cone_runs_as_in_the_whole_system_whatever_the_rest_does(text, seed):
    """The theorem of §4.0 against the reference simulator, on random systems with sporadic sources,
    compounds, prescalers, cooperative siblings, delay and execution-time ranges: the cone's jobs and
    the chain's samples are the same in the subsystem, in the whole system, and in the whole system
    with every choice outside the cone drawn anew."""
    model = verify.load_text(text, "random.vfy").system()
    horizon = F(3, 2)
    a = random_scenario(model, random.Random(f"{seed}/a"), horizon)
    b = random_scenario(model, random.Random(f"{seed}/b"), horizon)
    whole = simulate(model, a)
    roots = [(c.name, list(c.tasks)) for c in model.chains] + [(None, [t.id]) for t in model.tasks]
    for name, tasks in roots:
        inside = cone(model, tasks)
        sub = restrict(model, inside, {name} if name else set())
        assert [t.id for t in sub.tasks] == [t.id for t in model.tasks if t.id in inside]
        alone = simulate(sub, a)
        other = simulate(model, _mixed(a, b, inside, model))
        assert _timing(alone, inside) == _timing(whole, inside) == _timing(other, inside), (name, tasks, text)
        if name:
            c_whole = next(c for c in model.chains if c.name == name)
            expected = chain_latencies(whole, c_whole)
            assert chain_latencies(alone, sub.chains[0]) == expected, (name, text)
            assert chain_latencies(other, c_whole) == expected, (name, text)


def test_the_cone_follows_triggers_priorities_and_siblings():
    ts = [task("s.W", timer(10), prio=3, core="c1", produces=["o"]),            # writer of the trigger
          task("r.R", trigger("i"), prio=5, core="c0", reads=["i"], produces=["o"]),
          task("h.H", timer(4), prio=6, core="c0"),                                # higher priority: in
          task("e.E", timer(5), prio=5, core="c0"),                                # equal priority: in
          task("l.L", timer(3), prio=4, core="c0", bcet=F(1, 2) * MS),            # lower priority: out
          task("q.Q", timer(7), prio=9, core="c2", bcet=F(1, 2) * MS),            # another core: out
          task("x.A", timer(20), prio=2, core="c1", kind="cooperative"),          # coop...
          task("x.B", timer(20), prio=1, core="c2", kind="cooperative")]          # ...siblings
    ls = [link("s.o", "r.i", ts)]
    sysm = system(ts, ls, [chain("ch", ["s.W", "r.R"], ls)])
    assert cone(sysm, ["s.W", "r.R"]) == {"s.W", "r.R", "h.H", "e.E"}
    # a cooperative task brings its siblings, and they bring their cores' higher priorities
    assert cone(sysm, ["x.A"]) == {"x.A", "x.B", "s.W", "q.Q"}


def _with_outside_noise(sysm):
    """``sysm`` plus tasks its chain cannot see: one with an execution-time range on a core of its
    own, one sporadic below everything on c0, and one reading the chain's output with a delay range."""
    lowest = min(t.priority for t in sysm.tasks) - 1
    noise = [task("n.Range", timer(5), wcet=2 * MS, bcet=MS, prio=3, core="c9"),
             task("n.Spor", verify.model.system.SporadicSource(4 * MS, 9 * MS), prio=lowest, core="c0"),
             task("n.Read", timer(6), prio=lowest - 1, core="c1", reads=["i"], bcet=MS / 2)]
    last = sysm.chains[0].tasks[-1]
    inst = last.split(".")[0]
    links = sysm.links + (verify.model.system.LinkModel(f"{inst}.o", "n.i", last, ("n.Read",), MS, 3 * MS),)
    return system(sysm.tasks + tuple(noise), links, sysm.chains)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rigid_systems())
def test_the_exact_worst_case_of_a_cone_is_that_of_the_whole_rigid_system(sysm):
    """Tasks outside a chain's cone with ranges and sporadic releases do not keep ``prove`` from the
    exact search, and the exact worst case it reports is the one enumeration finds on the system
    without them."""
    noisy = _with_outside_noise(sysm)
    assert exact_class(noisy) is not None and exact_class(sysm) is None
    targets = [Target(k, "ch") for k in KINDS]
    ex = enumerate_exact(sysm, targets, Budget(3000))
    if ex is None or not ex.complete:
        return  # too many representatives for a quick test
    low = sysm.chains[0]
    specs = {"reaction_time": ex.worst[targets[0]].value, "data_age": ex.worst[targets[1]].value}
    specs = {k: v for k, v in specs.items() if v is not None}
    spec_model = system(noisy.tasks, noisy.links,
                        [chain(low.name, low.tasks, noisy.links, **{k: v - MS / 4 for k, v in specs.items()})])
    result = prove(spec_model, budget=3000)
    for kind, worst in specs.items():
        v = result.verdict("ch", kind)
        if v.method == "bound":
            continue
        assert v.method == "exact-enumeration", (v.status, v.note)
        assert v.exact == worst and v.status == "violated"
        cex = v.counterexample  # found on the cone, replayed on the whole noisy system
        trace = replay(spec_model, cex.scenario)
        samples = getattr(chain_latencies(trace, spec_model.chains[0]), kind)
        assert cex.sample in samples and cex.latency > v.spec


def test_a_range_outside_the_cone_no_longer_leaves_a_spec_undecided():
    """The chain H → L of ``test_undecided_outside_the_exact_class`` (1 ms between them) with constant
    times, and a task with an execution-time range on another core: exactly proved (it was undecided)."""
    ts = [task("c.H", timer(10), wcet=5 * MS, prio=2, produces=["o"]),
          task("m.L", trigger("i"), wcet=MS, prio=1, reads=["i"]),
          task("o.N", timer(3), wcet=2 * MS, bcet=MS / 2, prio=1, core="c1")]
    ls = [link("c.o", "m.i", ts, dmin=MS)]
    sysm = system(ts, ls, [chain("ctl", ["c.H", "m.L"], ls, reaction_time=F(18, 1000))])
    assert exact_class(sysm) is not None
    v = prove(sysm, budget=60).verdict("ctl", "reaction_time")
    assert (v.status, v.method) == ("proved", "exact-enumeration")
    assert v.exact == F(17, 1000) and v.bound > v.spec  # H's release to L's completion, past one period


def test_undecided_cones_share_the_budget_of_the_falsifying_search():
    """Two independent chains, each undecided (an execution-time range in its cone): the falsifying
    search of the first cone does not use up the budget of the second. The two first scenarios run
    once for both (on the union of the cones); each search then has half of the 98 left."""
    ts, ls, cs = [], [], []
    for n, core in ((1, "c0"), (2, "c1")):
        ts += [task(f"c{n}.H", timer(10), wcet=5 * MS, bcet=4 * MS, prio=2, core=core, produces=["o"]),
               task(f"m{n}.L", trigger("i"), wcet=MS, prio=1, core=core, reads=["i"])]
        ls.append(link(f"c{n}.o", f"m{n}.i", ts, dmin=MS))  # (no pipeline: the bound stays above the spec)
    for n in (1, 2):
        cs.append(chain(f"ctl{n}", [f"c{n}.H", f"m{n}.L"], ls, reaction_time=F(18, 1000)))
    result = prove(system(ts, ls, cs), budget=100)
    verdicts = [result.verdict(f"ctl{n}", "reaction_time") for n in (1, 2)]
    assert [v.status for v in verdicts] == ["undecided", "undecided"]
    assert [v.explored for v in verdicts] == [2 + 49, 2 + 49] and result.explored == 100


def test_budget_a_batch_leaves_goes_to_the_cones_still_undecided(monkeypatch):
    """Two independent chains in one batch: the first is refuted by the shared first runs and uses
    nothing of its half of the budget; the second's search, undecided after its half, resumes in a
    second round with what the first left, so the whole budget is used — the same in one process
    and spread over two."""
    import verify.prove.core as core

    ts, ls = [], []
    for n, core_name in ((1, "c0"), (2, "c1")):
        ts += [task(f"c{n}.H", timer(10), wcet=5 * MS, bcet=4 * MS, prio=2, core=core_name, produces=["o"]),
               task(f"m{n}.L", trigger("i"), wcet=MS, prio=1, core=core_name, reads=["i"])]
        ls.append(link(f"c{n}.o", f"m{n}.i", ts, dmin=MS))  # (no pipeline: the bound stays above the spec)
    cs = [chain("ctl1", ["c1.H", "m1.L"], ls, reaction_time=F(3, 1000)),  # below every run's latency
          chain("ctl2", ["c2.H", "m2.L"], ls, reaction_time=F(18, 1000))]
    result = prove(system(ts, ls, cs), budget=100, jobs=1)
    first, second = (result.verdict(f"ctl{n}", "reaction_time") for n in (1, 2))
    assert (first.status, first.method, first.explored) == ("violated", "search", 2)
    assert (second.status, second.explored) == ("undecided", 2 + 98) and result.explored == 100
    monkeypatch.setattr(core, "PARALLEL_TASK_SCENARIOS", 0)
    assert prove(system(ts, ls, cs), budget=100, jobs=2) == result


def test_a_counterexample_that_does_not_carry_over_is_decided_on_the_whole_system(monkeypatch):
    """The fallback for a bug in the cone (it has none we know of): the group is decided again on the
    whole system, whose verdicts are those without cones."""
    import verify.prove.core as core
    from verify.prove.cone import SliceMismatch

    ts = [task("c.H", timer(10), wcet=5 * MS, prio=2, produces=["o"]),
          task("m.L", trigger("i"), wcet=MS, prio=1, reads=["i"]),
          task("o.N", timer(3), wcet=2 * MS, bcet=MS / 2, prio=1, core="c1")]
    ls = [link("c.o", "m.i", ts)]
    sysm = system(ts, ls, [chain("ctl", ["c.H", "m.L"], ls, reaction_time=F(15, 1000))])
    calls = []

    def mismatch(model, cexs, *_):
        calls.append(model)
        raise SliceMismatch("test")

    monkeypatch.setattr(core, "check_all_carry_over", mismatch)
    v = prove(sysm, budget=200).verdict("ctl", "reaction_time")
    assert calls == [sysm]
    # on the whole system the range keeps the exact search away: a falsifying search refutes it
    assert (v.status, v.method) == ("violated", "search")
    trace = replay(sysm, v.counterexample.scenario)
    assert v.counterexample.sample in chain_latencies(trace, sysm.chains[0]).reaction_time


@pytest.mark.slow
def test_the_searches_of_the_cones_give_the_same_verdicts_side_by_side(monkeypatch):
    """A generated system whose specs are half their reference bound leaves many cones to the
    falsifying search; run in one process or spread over two (the batches forced parallel), every
    verdict — status, explored scenarios, counterexample — is the same, and each counterexample
    replays on the whole system in the reference simulator."""
    import verify.prove.core as core
    from benchmarks.generate import generate_system

    model = verify.load_text(generate_system(40, seed=3, chains=8, tightness=F(1, 2)), "w.vfy").system()
    one = prove(model, budget=30, jobs=1)
    monkeypatch.setattr(core, "PARALLEL_TASK_SCENARIOS", 0)
    two = prove(model, budget=30, jobs=2)
    assert one == two
    searched = [v for v in one.verdicts if v.method == "search"]
    assert len({v.name for v in searched}) > core.SEARCH_BATCH  # more cones than one batch
    assert any(v.status == "violated" for v in searched) and one.explored <= 30
    for v in searched:
        if v.counterexample is not None and v.subject == "chain":
            trace = replay(model, v.counterexample.scenario)
            c = next(c for c in model.chains if c.name == v.name)
            assert v.counterexample.sample in getattr(chain_latencies(trace, c), v.kind)


@pytest.mark.slow
def test_every_cone_starts_from_the_shared_first_runs():
    """The first two scenarios of every search (all phases 0 with wcet and d⁺, then with bcet and d⁻)
    run once on the union of the cones: with a budget of 4 scenarios and more than four cones to
    search, every searched obligation was still measured on those two runs, and what they refute
    replays on the whole system."""
    from benchmarks.generate import generate_system

    model = verify.load_text(generate_system(40, seed=3, chains=8, tightness=F(1, 2)), "w.vfy").system()
    result = prove(model, budget=4)
    searched = [v for v in result.verdicts if v.method == "search"]
    assert len({v.name for v in searched}) > 4 and result.explored <= 4
    assert all(v.explored >= 2 for v in searched)
    assert any(v.status == "violated" for v in searched)
    for v in searched:
        if v.counterexample is not None and v.subject == "chain":
            trace = replay(model, v.counterexample.scenario)
            c = next(c for c in model.chains if c.name == v.name)
            assert v.counterexample.sample in getattr(chain_latencies(trace, c), v.kind)
