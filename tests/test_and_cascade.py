"""AND joins of one cascade (specs/timing.md §7.3, (7.3e)): a task released by time writes to an AND
join directly and through a task it triggers; the join then fires at the arrival of the triggered
task's value, so neither the reaction time nor the data age waits for the other members. Known
answers, the rule's conditions, the bounds held to the simulator and prove's search, and synth's
encoding following the rule."""
from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.timing import analyze, timing_of
from verify.timing.chains import cascade_fresh, cascade_links

from .test_synth_properties import _encoded_bounds_match
from .test_trigger_hop_bounds import _ms, assert_no_run_beyond_the_bounds

MS = Fraction(1, 1000)

CONTROL = """
component Plan { out o : T
  task P { produces o  bcet 9 ms  wcet 10 ms } }
component Ctl { in a : T  out o : T
  task C { reads a  produces o  bcet 9 ms  wcet 10 ms } }
component Fuse { in x : T  in y : T  in both = x & y  out o : T
  task F { reads x  reads y  produces o  bcet 9 ms  wcet 10 ms } }

system S {
  core c0
  instance plan : Plan on c0 { task P priority 30 timer 100 ms }
  instance ctl : Ctl on c0 { task C priority 29 trigger a }
  instance fuse : Fuse on c0 { task F priority 28 trigger both }
  connect plan.o -> ctl.a
  connect plan.o -> fuse.y{y_delay}
  connect ctl.o -> fuse.x
  chain control: plan.o -> ctl.o -> fuse.o
}
"""


def _control(y_delay=""):
    return verify.load_text(CONTROL.replace("{y_delay}", y_delay), "control.vfy").system()


def test_the_join_of_one_cascade_fires_at_the_last_arrival():
    model = _control()
    chain = analyze(model).chain("control")
    # the planner's value reaches the join before the controller's, which completes the set, so no hop
    # waits for the planner's next output: the reaction is W⁺ 100 + R(plan) 10 + R(ctl) 10 + R(fuse)
    # 30 ms (the runs reach 130 ms), the data age R(plan) 10 + R(ctl) 10 + R(fuse) 30 ms (runs: 30 ms)
    steps = {s.label: s for s in chain.steps}
    join = steps["ctl.C → fuse.F"]
    assert dict(join.reaction.parts)["wait for the other members"] == 0
    assert dict(join.data_age.parts)["wait for the other members"] == 0
    assert (chain.bound("reaction_time").worst, chain.bound("data_age").worst) == (150 * MS, 50 * MS)
    (hop,) = [h for h in model.chains[0].hops if h.reader == "fuse.F"]
    feed, others = cascade_links(model, hop, model.task("fuse.F").activation, model.task("ctl.C").activation)
    assert feed.writer == "plan.P" and [lk.source for lk in others] == ["plan.o"]
    assert cascade_fresh(timing_of(analyze(model), model), hop)


def test_a_slower_direct_connection_keeps_the_wait():
    """With the planner's value delayed past the controller's (``d⁺ > C⁻ₚ``), the join may fire at the
    next planner output: the rule does not apply and the bound keeps the wait."""
    model = _control(" delay 0 ms .. 15 ms")
    (hop,) = [h for h in model.chains[0].hops if h.reader == "fuse.F"]
    assert not cascade_fresh(timing_of(analyze(model), model), hop)
    assert analyze(model).chain("control").bound("data_age").worst > 100 * MS


@st.composite
def cascade_systems(draw, holes: bool = False) -> str:
    """w (released by time) → p (triggered) → i (AND of p's output and one or two of w's), with delays,
    execution-time ranges, one or two cores, priorities that may tie, a prescaler on p or i now and
    then, an interfering task, and the chain w → p → i (→ z) or a part of it; with ``holes``, w's
    period, p's prescaler or w's activation kind may be left to synthesis."""
    cores = draw(st.sampled_from([["c0"], ["c0", "c1"]]))

    def core():
        return draw(st.sampled_from(cores))

    def times(hi=6):
        wcet = Fraction(draw(st.integers(1, hi)), 2)
        return _ms(wcet * Fraction(draw(st.integers(0, 4)), 4)), _ms(wcet)

    def prio():
        return draw(st.integers(1, 4))

    def delay():
        return f" delay {draw(st.sampled_from([0, 1]))} ms .. {draw(st.sampled_from([1, 2, 6]))} ms" \
            if draw(st.integers(0, 3)) == 0 else ""

    period = draw(st.sampled_from([10, 20, 40]))
    source = (f"sporadic {period} ms .. {period * 2} ms" if draw(st.integers(0, 3)) == 0 else f"timer {period} ms")
    two = draw(st.booleans())  # a second member fed by w
    wb, ww = times()
    pb, pw = times()
    ib, iw = times()
    p_every = " every 2" if draw(st.integers(0, 5)) == 0 else ""
    if holes:
        source = draw(st.sampled_from([source, "timer ? in 10 ms .. 40 ms step 10 ms", "activation ?"]))
        p_every = draw(st.sampled_from([p_every, " every ? in 1 .. 2"]))
    i_every = " every 2" if draw(st.integers(0, 5)) == 0 else ""
    members = "x & y & v" if two else "x & y"
    text = [f"component W {{ out o : T\n  task T {{ produces o  bcet {wb}  wcet {ww} }} }}",
            f"component P {{ in a : T  out o : T\n  task T {{ reads a  produces o  bcet {pb}  wcet {pw} }} }}",
            f"component I {{ in x : T  in y : T  in v : T  in j = {members}  out o : T\n"
            f"  task T {{ reads x  reads y  reads v optional  produces o  bcet {ib}  wcet {iw} }} }}",
            "component Z { in a : T  out o : T\n  task T { reads a  produces o  bcet 1/2 ms  wcet 1 ms } }",
            "component H {\n  task T { bcet 1 ms  wcet 2 ms } }",
            "", "system S {", *(f"  core {c}" for c in cores),
            f"  instance w : W on {core()} {{ task T priority {prio()} {source} }}",
            f"  instance p : P on {core()} {{ task T priority {prio()} trigger a{p_every} }}",
            f"  instance i : I on {core()} {{ task T priority {prio()} trigger j{i_every} }}",
            f"  connect w.o -> p.a{delay()}",
            f"  connect p.o -> i.x{delay()}",
            f"  connect w.o -> i.y{delay()}"]
    if two:
        text.append(f"  connect w.o -> i.v{delay()}")
    chain = ["w.o", "p.o", "i.o"]
    if draw(st.booleans()):
        text.append(f"  instance z : Z on {core()} {{ task T priority {prio()} trigger a }}")
        text.append(f"  connect i.o -> z.a{delay()}")
        chain.append("z.o")
    if draw(st.booleans()):
        every = draw(st.sampled_from([5, 10]))
        text.append(f"  instance h : H on {core()} {{ task T priority {prio()} timer {every} ms }}")
    first = draw(st.integers(0, 1))
    text.append("  chain ch: " + " -> ".join(chain[first:]))
    return "\n".join(text) + "\n}\n"


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(cascade_systems(), st.integers(0, 2**16))
def test_no_run_beyond_the_bounds_of_cascades(text, seed):
    loaded = verify.load_text(text, "cascade.vfy")
    assert loaded.ok, [(d.code, d.message) for d in loaded.diagnostics] + [text]
    assert_no_run_beyond_the_bounds(loaded.system(), text, f"cascade/{seed}")


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(cascade_systems(holes=True))
def test_the_encoded_bounds_of_cascades_are_the_analysis_bounds(text):
    """Synth's encoding follows (7.3e) for every configuration, also where the period or kind of ``w``
    or the prescaler of ``p`` is chosen (``_encoded_bounds_match``)."""
    _encoded_bounds_match(text)
