"""The pipeline release offsets of specs/timing.md §6.2 (``verify.timing.pipeline``).

* A known answer: three stages of 10 ms on one core, each released by the one before at a higher
  priority. The plain busy window charges each stage its predecessors' jobs (10, 20, 30 ms); a stage
  is released only once they have run, so each responds within 10 ms, as every run shows.
* A Hypothesis property: pipelines of two to four stages on one core (timers and sporadic sources,
  prescalers, execution-time ranges, a delay sometimes, a branch, an interfering task, priorities
  from a small set), with no simulated response or latency beyond the bounds and none found by
  prove's search; ``fastrta`` agrees with ``rta`` round by round.
"""
from __future__ import annotations

import random
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.prove.sim import random_scenario, simulate
from verify.timing import analyze
from verify.timing.pipeline import upstream
from verify.timing.rta import cooperative_counts

from .test_bounds_vs_simulation import _slowest
from .test_perf_equivalence import _rounds_agree
from .test_timing import bound_violations
from .test_trigger_hop_bounds import assert_no_run_beyond_the_bounds

MS = Fraction(1, 1000)

THREE = """
component Src { out o : T
  task T { produces o  bcet 10 ms  wcet 10 ms } }
component Stage { in i : T  out o : T
  task T { reads i  produces o  bcet 10 ms  wcet 10 ms } }
system S {
  core c
  instance s0 : Src on c { task T priority 3 timer 100 ms }
  instance s1 : Stage on c { task T priority 2 trigger i }
  instance s2 : Stage on c { task T priority 1 trigger i }
  connect s0.o -> s1.i
  connect s1.o -> s2.i
  chain ch: s0.o -> s1.o -> s2.o
}
"""


def test_known_answer_three_stages():
    """s2's path is s1, s0 (``upstream``). Its cases: s1's job completed at the window's start (s1
    and s0 each count ⌈(w + X)/100 ms⌉ − 1 = 0 jobs: w = 10 ms from a₁ = t₀), or the cascade's
    first job in the window is s1's (w = 20 ms, of which s1's 10 ms run before a₁) or s0's (w =
    30 ms, 20 ms before a₁): 10 ms each. The busy window alone gives 30 ms. Every run reaches 10 ms
    for every stage."""
    model = verify.load_text(THREE, "three.vfy").system()
    assert [t.id for t, _ in upstream(model, model.task("s2.T"), cooperative_counts(model))] == ["s1.T", "s0.T"]
    analysis = analyze(model)
    assert [analysis.task(t).wcrt for t in ("s0.T", "s1.T", "s2.T")] == [10 * MS] * 3
    trace = simulate(model, _slowest(random_scenario(model, random.Random(1), Fraction(1)), model))
    for tid in ("s0.T", "s1.T", "s2.T"):
        assert max(j.finish - j.release for j in trace.jobs[tid] if j.finish is not None) == 10 * MS
    assert bound_violations(model, trace) == []
    assert analysis.chain("ch").bound("reaction_time").worst == 100 * MS + 30 * MS  # W⁺₁ + R₁ + R₂ + R₃
    _rounds_agree(model)


def test_a_delay_or_a_lower_priority_writer_is_no_pipeline():
    """The path stops at a connection with a delay and at a writer of lower priority."""
    delayed = verify.load_text(THREE.replace("connect s1.o -> s2.i", "connect s1.o -> s2.i delay 1 ms .. 1 ms"),
                               "d.vfy").system()
    assert upstream(delayed, delayed.task("s2.T"), {}) == ()
    swapped = verify.load_text(THREE.replace("priority 1 trigger", "priority 4 trigger"), "s.vfy").system()
    assert upstream(swapped, swapped.task("s2.T"), {}) == ()


def _ms(value: Fraction) -> str:
    return f"{value.numerator}/{value.denominator} ms" if value.denominator != 1 else f"{value.numerator} ms"


@st.composite
def pipelines(draw) -> str:
    """A pipeline s0 → … → s(n−1) on core c, a branch b off one stage sometimes, and an interfering
    task h, as DSL text."""
    n = draw(st.integers(2, 4))
    period = draw(st.sampled_from([10, 20, 40]))

    def times() -> tuple[Fraction, Fraction]:
        wcet = Fraction(draw(st.integers(1, 8)), 2)
        return wcet * Fraction(draw(st.integers(0, 4)), 4), wcet

    comps, insts, conns = [], [], []
    for k in range(n + 2):
        b, w = times()
        reads = "" if k == 0 else "reads i  "
        port = "" if k == 0 else "in i : T  "
        comps.append(f"component C{k} {{ {port}out o : T\n"
                     f"  task T {{ {reads}produces o  bcet {_ms(b)}  wcet {_ms(w)} }} }}")
    source = (f"sporadic {period} ms .. {period * 2} ms" if draw(st.integers(0, 3)) == 0 else f"timer {period} ms")
    insts.append(f"  instance s0 : C0 on c {{ task T priority {draw(st.integers(1, 5))} {source} }}")
    for k in range(1, n):
        every = f" every {draw(st.sampled_from([2, 3]))}" if draw(st.integers(0, 4)) == 0 else ""
        insts.append(f"  instance s{k} : C{k} on c {{ task T priority {draw(st.integers(1, 5))} trigger i{every} }}")
        delay = " delay 0 ms .. 1 ms" if draw(st.integers(0, 5)) == 0 else ""
        conns.append(f"  connect s{k - 1}.o -> s{k}.i{delay}")
    if draw(st.booleans()):
        at = draw(st.integers(0, n - 1))
        insts.append(f"  instance b : C{n} on c {{ task T priority {draw(st.integers(1, 5))} trigger i }}")
        conns.append(f"  connect s{at}.o -> b.i")
    if draw(st.booleans()):
        other = draw(st.sampled_from([5, 10, 25]))
        insts.append(f"  instance h : C0 on c {{ task T priority {draw(st.integers(1, 5))} timer {other} ms }}")
    chain = " -> ".join(f"s{k}.o" for k in range(n))
    return ("\n".join(comps) + "\n\nsystem S {\n  core c\n" + "\n".join(insts) + "\n" + "\n".join(conns)
            + f"\n  chain ch: {chain}\n}}\n")


@pytest.mark.slow
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(pipelines(), st.integers(0, 2**16))
def test_no_run_beyond_the_bounds_of_pipelines(text, seed):
    loaded = verify.load_text(text, "pipeline.vfy")
    assert loaded.ok, [(d.code, d.message) for d in loaded.diagnostics] + [text]
    model = loaded.system()
    _rounds_agree(model)
    assert_no_run_beyond_the_bounds(model, text, f"pipeline/{seed}")
