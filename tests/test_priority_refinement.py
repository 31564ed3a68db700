"""The same-core priority rule (specs/timing.md §7.6) against the independent simulator.

A hop p → i whose writer and reader share a core, where p's priority is strictly higher than i's,
the connection's delay is exactly 0 and p cannot wait for a cooperative token while i starts, gets
the data-age term ``A⁺ₚ`` (equation (7.6a)) instead of ``d⁺ + A⁺ₚ + Rₚ`` and the reaction term
``W⁺ᵢ + Rᵢ − Rₚ`` (equation (7.6b)) instead of ``d⁺ + W⁺ᵢ + Rᵢ``.

* Known answers on a two-task core (p: 10 ms timer, priority 2, wcet 3 ms; q: 10 ms timer,
  priority 1, wcet 1 ms), with the runs that come within 10 us of each refined bound.
* The conditions: with a delay, or with a writer whose cooperative sibling on another core holds
  the token, a concrete run exceeds what the rule would give; with equal priorities the reader
  can start while a job of the writer is pending (FIFO, §1) — in each case the analysis keeps the
  register rule.
* A Hypothesis property: random small systems built around such a hop (writer and reader on one
  core with drawn priorities, delays, activations, cooperative siblings, an interfering task, an
  upstream writer and a downstream reader) — no simulated latency beyond the analytic bounds, and
  the rule is used exactly when its conditions hold.
"""
from __future__ import annotations

import random
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.prove.sim import KINDS, Scenario, chain_latencies, random_scenario, simulate
from verify.timing import analyze
from verify.timing.chains import READ_AGE, REGISTER, SAME_CORE

from .test_bounds_vs_simulation import _slowest
from .test_timing import bound_violations

MS = Fraction(1, 1000)
US = Fraction(1, 1_000_000)
#: simulated worst / analytic bound per latency kind, for chains where the §7.6 rule is used
TIGHTNESS: dict[str, list[Fraction]] = {kind: [] for kind in KINDS}

PRIO = """
component P {
  out o : T
  task W {
    produces o
    bcet 1 ms
    wcet 3 ms
  }
}
component Q {
  in a : T
  task R {
    reads a
    bcet 1 ms
    wcet 1 ms
  }
}
system S {
  core c0
  instance p : P on c0 {
    task W priority PW timer 10 ms
  }
  instance q : Q on c0 {
    task R priority 1 timer 10 ms
  }
  connect p.o -> q.a DELAY
  chain ch: p.o -> q.a
}
"""

HIGH = """
component H {
  task T {
    wcet 2 ms
  }
}
system S {
  instance h : H on c0 {
    task T priority 5 timer 10 ms
  }
"""


def _prio_system(writer_priority: int = 2, delay: str = "", high: bool = False):
    text = PRIO.replace("PW", str(writer_priority)).replace("DELAY", delay)
    if high:  # an interfering task of the highest priority on c0
        head, tail = HIGH.split("system S {")
        text = head + text.replace("system S {\n  core c0\n", "system S {\n  core c0\n" + tail.lstrip("\n"))
    result = verify.load_text(text, "prio.vfy")
    assert result.ok, [d.message for d in result.diagnostics]
    return result.system()


def _worst(model, scenario, kind):
    return chain_latencies(simulate(model, scenario), model.chains[0]).worst(kind).value


def test_known_answer_two_tasks_on_one_core():
    """R(p) = 3 ms; R(q) = 1 + 3 = 4 ms (p preempts once); A⁺ = W⁺ = 10 ms for both timers.

    Data age (7.6a): A⁺(p) 10 + R(q) 4 = 14 ms (the register rule: d⁺ 0 + A⁺(p) 10 + R(p) 3 +
    R(q) 4 = 17 ms). Reaction (7.6b): W⁺(p) 10 + R(p) 3 + [W⁺(q) 10 + R(q) 4 − R(p) 3] = 24 ms
    (register rule: 27 ms); reduced 14 ms; non-reduced data age A⁺(p) 10 + 14 = 24 ms.

    The run with p at phase 0 and q at 9.99 ms: q starts at 9.99 ms and reads p's job of 0 ms
    (stamp 0), p's next job preempts it at 10 ms for 3 ms, q completes at 13.99 ms: data age
    13.99 ms. The stimulus just after p's read at 0 is first read by p's job of 10 ms (done at
    13 ms), whose output q's job of 19.99 ms reads; it completes at 23.99 ms: reaction 23.99 ms.
    """
    model = _prio_system()
    c = analyze(model).chain("ch")
    hop = c.steps[1]
    assert hop.data_age.rule == SAME_CORE and hop.reaction.rule == SAME_CORE
    assert hop.data_age.parts == (("A⁺(p.W)", 10 * MS),)
    assert hop.reaction.parts == (("W⁺(q.R)", 10 * MS), ("R(q.R)", 4 * MS), ("R(p.W)", -3 * MS))
    assert c.bound("data_age").worst == 14 * MS
    assert c.bound("reaction_time").worst == 24 * MS
    assert c.bound("reaction_time_reduced").worst == 14 * MS
    assert c.bound("data_age_nonreduced").worst == 24 * MS
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "q.R": Fraction(999, 100_000)})
    assert _worst(model, scenario, "data_age") == 14 * MS - 10 * US
    assert _worst(model, scenario, "reaction_time") == 24 * MS - 10 * US
    assert _worst(model, scenario, "data_age_nonreduced") == 24 * MS - 10 * US
    assert bound_violations(model, simulate(model, scenario)) == []


def test_equal_priorities_keep_the_register_rule():
    """With equal priorities (FIFO, §1) the reader may start while a job of the writer is pending:
    p and q at priority 1, h (priority 5, 2 ms) and q released at 9.99 ms, p at 10 ms. h runs until
    11.99 ms; then q, released before p's job, starts first and reads p's job of 0 ms while p's
    job of 10 ms waits. The analysis keeps the register rule: R(p) = 3 + 1 + 2 = 6 ms,
    R(q) = 1 + 3 + 2 = 6 ms, data age d⁺ 0 + A⁺(p) 10 + R(p) 6 + E(q) 3 = 19 ms — the register
    rule bounds q's age at its read, and from its read q's job completes within E(q) = 1 + 2 ms
    (§7.7: h may preempt it, p, a timer of q's priority, may not), not R(q) = 6 ms. (§7.6 explains
    why the bound of (7.6a) would still hold here, and why the rule is not used.)"""
    model = _prio_system(writer_priority=1, high=True)
    c = analyze(model).chain("ch")
    assert c.steps[1].data_age.rule == REGISTER and c.steps[1].reaction.rule == REGISTER
    assert c.steps[2].data_age.rule == READ_AGE and c.steps[2].data_age.parts == (("E(q.R)", 3 * MS),)
    assert c.bound("data_age").worst == 19 * MS
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "q.R": Fraction(999, 100_000),
                                          "h.T": Fraction(999, 100_000)})
    trace = simulate(model, scenario)
    q = next(j for j in trace.jobs["q.R"] if j.release == Fraction(999, 100_000))
    p = next(j for j in trace.jobs["p.W"] if j.release == Fraction(1, 100))
    assert q.start == Fraction(1199, 100_000) and p.release < q.start < p.start
    assert q.read("q.a").job == 0
    assert bound_violations(model, trace) == []


def test_a_delay_disables_the_rule_and_the_refined_value_would_be_exceeded():
    """With a 1 ms delay, q's job started after p's completion may still read the old value: p's
    job of 10 ms writes at 13 ms, the value arrives at 14 ms; q's job of 13.5 ms (phase 3.5 ms)
    reads p's job of 0 ms (stamp 0) and completes at 14.5 ms: 14.5 ms > the 14 ms that (7.6a) would
    give (A⁺(p) 10 + R(q) 4)."""
    model = _prio_system(delay="delay 1 ms")
    c = analyze(model).chain("ch")
    assert c.steps[1].data_age.rule == REGISTER and c.steps[1].reaction.rule == REGISTER
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "q.R": Fraction(35, 10_000)})
    observed = _worst(model, scenario, "data_age")
    assert observed == Fraction(145, 10) * MS > 14 * MS
    assert observed <= c.bound("data_age").worst
    assert bound_violations(model, simulate(model, scenario)) == []


COOP = """
component P {
  out o : T
  task W cooperative {
    produces o
    bcet 3 ms
    wcet 3 ms
  }
  task S cooperative {
    bcet 4 ms
    wcet 4 ms
  }
}
component Q {
  in a : T
  task R {
    reads a
    bcet 1 ms
    wcet 1 ms
  }
}
system S {
  core c0
  core c1
  instance p : P on c0 {
    task W priority 2 timer 20 ms
    task S priority 1 on c1 timer 40 ms
  }
  instance q : Q on c0 {
    task R priority 1 timer 20 ms
  }
  connect p.o -> q.a
  chain ch: p.o -> q.a
}
"""


def test_a_token_held_by_a_sibling_on_another_core_disables_the_rule():
    """p.W shares its instance's token with p.S on c1. With p at phase 0, S at 19 ms and q at
    2.9 ms: S holds the token over [19, 23) ms, so p's job of 20 ms cannot start, and q's job of
    22.9 ms on c0 starts at once and reads p's job of 0 ms (stamp 0); p's job then preempts it over
    [23, 26) ms and q completes at 26.9 ms: data age 26.9 ms, above the A⁺(p) 20 + R(q) 4 = 24 ms
    that (7.6a) would give. The analysis keeps the register rule: d⁺ 0 + A⁺(p) 20 + R(p) 11
    (3 + blocking 4 + S overtaking once more 4) + R(q) 4 = 35 ms."""
    result = verify.load_text(COOP, "coop.vfy")
    assert result.ok, [d.message for d in result.diagnostics]
    model = result.system()
    analysis = analyze(model)
    c = analysis.chain("ch")
    assert c.steps[1].data_age.rule == REGISTER and c.steps[1].reaction.rule == REGISTER
    assert (analysis.task("p.W").wcrt, analysis.task("q.R").wcrt) == (11 * MS, 4 * MS)
    assert c.bound("data_age").worst == 35 * MS
    scenario = Scenario(Fraction(1, 10), {"p.W": Fraction(0), "p.S": Fraction(19, 1000),
                                          "q.R": Fraction(29, 10_000)})
    trace = simulate(model, scenario)
    q = next(j for j in trace.jobs["q.R"] if j.release == Fraction(229, 10_000))
    assert q.start == q.release and q.read("q.a").job == 0 and q.finish == Fraction(269, 10_000)
    observed = chain_latencies(trace, model.chains[0]).worst("data_age").value
    assert observed == Fraction(269, 10) * MS > 24 * MS
    assert bound_violations(model, trace) == []


# ------------------------------------------------------------------ the property


def _ms(value: Fraction) -> str:
    return f"{value.numerator}/{value.denominator} ms" if value.denominator != 1 else f"{value.numerator} ms"


@st.composite
def hop_systems(draw) -> tuple[str, bool]:
    """A system around one hop p → q as DSL text, and whether §7.6's conditions hold for it."""
    periods = [5, 10, 20, 25, 40]
    same_core = draw(st.integers(0, 4)) > 0
    p_prio = draw(st.integers(2, 6))
    q_prio = p_prio - draw(st.sampled_from([1, 1, 2, 0, -1]))  # mostly lower, sometimes equal/higher
    delayed = draw(st.integers(0, 5)) == 0
    p_coop = draw(st.integers(0, 2)) == 0
    sibling = p_coop and draw(st.booleans())
    sibling_core = draw(st.sampled_from(["c0", "c1"]))
    q_in_p = p_coop and draw(st.integers(0, 3)) == 0  # q a cooperative task of p's own instance
    upstream = draw(st.booleans())

    def exec_times():
        wcet = Fraction(draw(st.integers(1, 8)), 2)
        return wcet * Fraction(draw(st.integers(0, 4)), 4), wcet

    def activation(port: str | None):
        kind = draw(st.sampled_from(["timer", "timer", "sporadic", "trigger"] if port else ["timer", "sporadic"]))
        period = draw(st.sampled_from(periods))
        if kind == "timer":
            return f"timer {period} ms"
        if kind == "sporadic":
            return f"sporadic {period} ms .. {_ms(Fraction(period * draw(st.integers(4, 8)), 4))}"
        k = draw(st.sampled_from([1, 1, 2]))
        return f"trigger {port}" + (f" every {k}" if k > 1 else "")

    comps, insts, conns, chain = [], [], [], []
    if upstream:
        b, w = exec_times()
        comps.append(f"component U {{\n  out o : T\n  task T {{\n    produces o\n    bcet {_ms(b)}\n"
                     f"    wcet {_ms(w)}\n  }}\n}}")
        insts.append(f"  instance u : U on {draw(st.sampled_from(['c0', 'c1']))} {{\n"
                     f"    task T priority {draw(st.integers(1, 7))} {activation(None)}\n  }}")
        conns.append("  connect u.o -> p.x")
        chain.append("u.o")
    pb, pw = exec_times()
    qb, qw = exec_times()
    p_kind = " cooperative" if p_coop else ""
    p_reads = "    reads x\n" if upstream else ""
    p_body = [f"  task W{p_kind} {{\n{p_reads}    produces o\n    bcet {_ms(pb)}\n    wcet {_ms(pw)}\n  }}"]
    p_bind = [f"    task W priority {p_prio} {activation('x' if upstream else None)}"]
    if sibling:
        sb, sw = exec_times()
        p_body.append(f"  task S cooperative {{\n    bcet {_ms(sb)}\n    wcet {_ms(sw)}\n  }}")
        p_bind.append(f"    task S priority {draw(st.integers(1, 7))} on {sibling_core} "
                      f"timer {draw(st.sampled_from(periods))} ms")
    q_act = activation("a")
    q_core = "c0" if same_core else "c1"
    q_body = (f"  task R{' cooperative' if q_in_p else ''} {{\n    reads a\n    produces r\n"
              f"    bcet {_ms(qb)}\n    wcet {_ms(qw)}\n  }}")
    q_bind = f"    task R priority {q_prio} on {q_core} {q_act}"
    ins = (["  in x : T"] if upstream else []) + ["  out o : T"]
    if q_in_p:
        ins += ["  in a : T", "  out r : T"]
        comps.append("component P {\n" + "\n".join(ins) + "\n" + "\n".join(p_body + [q_body]) + "\n}")
        insts.append("  instance p : P on c0 {\n" + "\n".join(p_bind + [q_bind]) + "\n  }")
        q_inst = "p"
    else:
        comps.append("component P {\n" + "\n".join(ins) + "\n" + "\n".join(p_body) + "\n}")
        insts.append("  instance p : P on c0 {\n" + "\n".join(p_bind) + "\n  }")
        comps.append("component Q {\n  in a : T\n  out r : T\n" + q_body + "\n}")
        insts.append(f"  instance q : Q on c0 {{\n{q_bind}\n  }}")
        q_inst = "q"
    conns.append(f"  connect p.o -> {q_inst}.a" + (f" delay 0 ms .. {draw(st.sampled_from([1, 2]))} ms"
                                                    if delayed else ""))
    chain += ["p.o", f"{q_inst}.r"]
    if draw(st.booleans()):  # an interfering task on c0
        b, w = exec_times()
        comps.append(f"component H {{\n  task T {{\n    bcet {_ms(b)}\n    wcet {_ms(w)}\n  }}\n}}")
        insts.append(f"  instance h : H on c0 {{\n    task T priority {draw(st.integers(1, 7))} "
                     f"timer {draw(st.sampled_from(periods))} ms\n  }}")
    if draw(st.booleans()):  # a downstream reader on c0, with the same rule possibly applying again
        b, w = exec_times()
        comps.append(f"component Z {{\n  in a : T\n  out o : T\n  task T {{\n    reads a\n    produces o\n"
                     f"    bcet {_ms(b)}\n    wcet {_ms(w)}\n  }}\n}}")
        insts.append(f"  instance z : Z on c0 {{\n    task T priority {draw(st.integers(1, 7))} "
                     f"{activation('a')}\n  }}")
        conns.append(f"  connect {q_inst}.r -> z.a")
        chain.append("z.o")
    applies = (same_core and p_prio > q_prio and not delayed
               and (not sibling or q_in_p))
    text = ("\n\n".join(comps) + "\n\nsystem S {\n  core c0\n  core c1\n" + "\n".join(insts) + "\n"
            + "\n".join(conns) + "\n  chain ch: " + " -> ".join(chain) + "\n}\n")
    return text, applies


@pytest.mark.slow
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(hop_systems(), st.integers(0, 2**16))
def test_no_simulated_latency_beyond_the_bounds_around_a_same_core_hop(drawn, seed):
    text, applies = drawn
    loaded = verify.load_text(text, "hop.vfy")
    assert loaded.ok, [(d.code, d.message) for d in loaded.diagnostics] + [text]
    model = loaded.system()
    analysis = analyze(model)
    chain = analysis.chain("ch")
    hop = next(s for s in chain.steps if s.kind == "hop" and s.writer == "p.W")
    p, q = analysis.task("p.W"), analysis.task(hop.reader)
    if not applies:
        assert SAME_CORE not in (hop.data_age.rule, hop.reaction.rule), text
    elif p.a_max is not None and p.wcrt is not None and q.wcrt is not None:
        # the rule is in effect: each term is at most its (7.6a)/(7.6b) value
        assert hop.data_age.value <= p.a_max, text
        assert hop.reaction.value <= q.sampling_wait + q.wcrt - p.wcrt, text
    used = any(SAME_CORE in (s.data_age.rule if s.data_age else "", s.reaction.rule if s.reaction else "")
               for s in chain.steps)
    for run in range(5):
        scenario = random_scenario(model, random.Random(f"{seed}/{run}"), Fraction(1))
        if run == 0:
            scenario = _slowest(scenario, model)
        trace = simulate(model, scenario)
        assert bound_violations(model, trace) == [], text
        if used:
            observed = chain_latencies(trace, model.chains[0])
            for kind in KINDS:
                bound, worst = chain.bound(kind).worst, observed.worst(kind)
                if bound and worst is not None:
                    TIGHTNESS[kind].append(worst.value / bound)


def tightness_summary() -> list[str]:
    """Lines for the tightness log (tests/conftest.py): how close the simulator came to the bounds
    of chains that use the same-core priority rule."""
    lines = []
    for kind, ratios in TIGHTNESS.items():
        if ratios:
            ordered = sorted(ratios)
            lines.append(f"{kind:28s} samples {len(ratios):4d}  max {float(ordered[-1]):.3f}  "
                         f"median {float(ordered[len(ordered) // 2]):.3f}  (simulated worst / analytic bound)")
    return lines
