"""The data-age rules of specs/timing.md §7.7 (ages at the read and at the completion) against the
independent simulator and prove's falsifying search.

* Known answers: a task whose equal-priority neighbour may delay its start but not its run (the
  start-to-completion time ``E``), a writer and the higher-priority reader it triggers on its core
  (the same-core trigger pair ``J``), an AND member whose value waits for a faster member (the AND
  join age), each with the run that reaches the bound where one does.
* The conditions: with a zero-time job that can trigger an equal-priority task of an earlier order,
  that task stays in ``E``'s interference; a pair whose reader has the lower priority, or a delay,
  is not one.

The Hypothesis property that holds these rules to the simulator and to prove's search, on small
systems around trigger hops, is ``tests/test_trigger_hop_bounds.py``.
"""
from __future__ import annotations

import random
from fractions import Fraction


import verify
from verify.prove.sim import Scenario, chain_latencies, random_scenario, simulate
from verify.timing import analyze
from verify.timing.chains import AND_AGE, LAST, PAIR, READ_AGE, REGISTER

from .test_timing import bound_violations

MS = Fraction(1, 1000)


def _load(text: str):
    result = verify.load_text(text, "ages.vfy")
    assert result.ok, [(d.code, d.message) for d in result.diagnostics]
    return result.system()


def _worst(model, scenario, kind="data_age"):
    return chain_latencies(simulate(model, scenario), model.chains[0]).worst(kind).value


# ------------------------------------------------------------------ start to completion (E)

TWO = """
component P {
  out o : T
  task W {
    produces o
    bcet 1 ms
    wcet 1 ms
  }
}
component Q {
  in a : T
  task T {
    reads a
    bcet QB ms
    wcet 1 ms
  }
}
component Z {
  out o : T
  task T {
    produces o
    bcet 0 ms
    wcet 1 ms
  }
}
system S {
  core c0
  core c1
  instance z : Z on c1 {
    task T priority 1 timer 10 ms
  }
  instance q : Q on c0 {
    task T priority 1 QACT
  }
  instance p : P on c0 {
    task W priority 1 timer 10 ms
  }
  connect z.o -> q.a
  chain ch: p.o
}
"""


def _two(qb="1/2", qact="timer 10 ms"):
    return _load(TWO.replace("QB", qb).replace("QACT", qact))


def test_start_to_completion_leaves_out_an_equal_priority_task_released_by_time():
    """q and p: 10 ms timers of priority 1 on c0, in this order, 1 ms each. R(p) = 2 ms (q, released
    at the same instant, runs first); once p's job has started, q's jobs rank after it: E(p) = 1 ms.
    The one-task chain's data age (from p's read to its completion) is E(p) = 1 ms, reached by every
    run; the non-reduced one A⁺(p) 10 + min(R − C⁻ = 1, 2 − 1) + 1 = 12 ms."""
    model = _two()
    c = analyze(model).chain("ch")
    assert analyze(model).task("p.W").wcrt == 2 * MS
    assert c.steps[-1].data_age.rule == READ_AGE and c.steps[-1].data_age.parts == (("E(p.W)", MS),)
    assert c.bound("data_age").worst == MS
    assert c.bound("data_age_nonreduced").worst == 12 * MS
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "q.T": Fraction(0)})
    assert _worst(model, scenario) == MS
    assert bound_violations(model, simulate(model, scenario)) == []


def test_a_zero_time_job_keeps_an_earlier_equal_priority_trigger_in_e():
    """q data-triggered by z (on c1, bcet 0): a job of z may complete at the instant p's job starts,
    and q, released at that instant after the dispatch and first in the order, ranks before p's job
    and preempts it — so q stays in E(p), which is then R(p) = 2 ms. With z's bcet above 0 it is
    left out again (no later round at an instant)."""
    zero = _two(qact="trigger a")
    assert analyze(zero).chain("ch").bound("data_age").worst == 2 * MS
    assert analyze(zero).chain("ch").steps[-1].data_age.rule == LAST
    # z and p released at 0, z runs for no time: q is released at 0 after p's dispatch and preempts it
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "z.T": Fraction(0)},
                        exec_time=lambda task, _i: Fraction(0) if task == "z.T" else MS)
    assert _worst(zero, scenario) == 2 * MS
    positive = _load(TWO.replace("QB", "1/2").replace("QACT", "trigger a").replace("bcet 0 ms", "bcet 1/2 ms"))
    assert analyze(positive).chain("ch").bound("data_age").worst == MS
    for model in (zero, positive):
        for seed in range(6):
            trace = simulate(model, random_scenario(model, random.Random(seed), Fraction(1, 5)))
            assert bound_violations(model, trace) == []


# ------------------------------------------------------------------ same-core trigger pair (J)

PAIR_TEXT = """
component P {
  out o : T
  task W {
    produces o
    bcet 2 ms
    wcet 2 ms
  }
}
component I {
  in a : T
  out o : T
  task T {
    reads a
    produces o
    bcet 1 ms
    wcet 1 ms
  }
}
component H {
  task T {
    bcet 1 ms
    wcet 1 ms
  }
}
system S {
  core c0
  instance p : P on c0 {
    task W priority 1 timer 20 ms
  }
  instance i : I on c0 {
    task T priority IP trigger a
  }
  instance h : H on c0 {
    task T priority 3 timer 10 ms
  }
  connect p.o -> i.a DELAY
  chain ch: p.o -> i.o
}
"""


def _pair(priority: int = 2, delay: str = ""):
    return _load(PAIR_TEXT.replace("IP", str(priority)).replace("DELAY", delay))


def test_known_answer_same_core_trigger_pair():
    """p (20 ms timer, priority 1, 2 ms) triggers i (priority 2, 1 ms) on c0, with h (10 ms timer,
    priority 3, 1 ms): E(p) = 2 + 1 = 3 ms, R(i) = 1 + 1 = 2 ms, and from p's read to i's completion
    the core runs p, i and at most one job of h: J(p, i) = 4 ms < 3 + 2. The data age 4 ms is reached
    when h is released 1 ms after p starts."""
    model = _pair()
    c = analyze(model).chain("ch")
    hop, last = c.steps[1], c.steps[2]
    assert hop.data_age.rule == PAIR and hop.data_age.parts == (("J(p.W, i.T)", 4 * MS),)
    assert last.data_age.rule == LAST and last.data_age.value == 0
    assert c.bound("data_age").worst == 4 * MS
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "h.T": MS})
    assert _worst(model, scenario) == 4 * MS
    assert bound_violations(model, simulate(model, scenario)) == []


def test_the_pair_needs_a_higher_priority_reader_and_no_delay():
    """With i at p's priority, or a 1 ms delay, the hop is no pair (i's job may wait for other work
    after p's completion, or p's core may idle while the value travels): the data trigger's term."""
    for model in (_pair(priority=1), _pair(delay="delay 1 ms .. 1 ms")):
        c = analyze(model).chain("ch")
        assert all(PAIR not in (s.data_age.rule if s.data_age else "") for s in c.steps)
        assert c.steps[1].data_age.rule in (READ_AGE, "data trigger k=1")
        for seed in range(6):
            trace = simulate(model, random_scenario(model, random.Random(seed), Fraction(1, 5)))
            assert bound_violations(model, trace) == []


# ------------------------------------------------------------------ AND join age

AND_TEXT = """
component P {
  out o : T
  task W {
    produces o
    bcet 1 ms
    wcet 1 ms
  }
}
component J {
  in a : T
  in b : T
  in both = a & b
  task T {
    reads a
    reads b
    bcet 1 ms
    wcet 1 ms
  }
}
system S {
  core c0
  core c1
  core c2
  instance p : P on c0 {
    task W priority 1 timer 30 ms
  }
  instance f : P on c1 {
    task W priority 1 timer 10 ms
  }
  instance j : J on c2 {
    task T priority 1 trigger both
  }
  connect p.o -> j.a
  connect f.o -> j.b
  chain ch: p.o -> j.T
}
"""


def test_known_answer_and_join_age():
    """p (30 ms timer) and f (10 ms timer) feed the AND of j on its own core. The register rule gives
    A⁺(p) 30 + R(p) 1 + R(j) 2 = 33 ms; the join fires within W⁺ of f's arrivals (its first arrival,
    F + R = 11 ms) after p's value arrives: R(p) 1 + 11 + R(j) 2 = 14 ms. The start-up run with f's
    first value at 11 ms and p's at 1 ms reaches 12 ms."""
    model = _load(AND_TEXT)
    c = analyze(model).chain("ch")
    hop = c.steps[1]
    assert hop.data_age.rule == AND_AGE
    assert hop.data_age.parts == (("d⁺", 0), ("R(p.W)", MS), ("wait for the other members", 11 * MS))
    assert c.bound("data_age").worst == 14 * MS
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "f.W": 10 * MS - Fraction(1, 10**6)})
    assert _worst(model, scenario) == 12 * MS - Fraction(1, 10**6)
    assert bound_violations(model, simulate(model, scenario)) == []


def test_the_register_rule_still_reports_where_nothing_is_tighter():
    """A timer reader on another core: register sampling, then R of the last task as before."""
    model = _load(AND_TEXT.replace("trigger both", "timer 10 ms"))
    c = analyze(model).chain("ch")
    assert c.steps[1].data_age.rule == REGISTER
