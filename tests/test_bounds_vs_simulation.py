"""Every analytic bound against the independent job-level simulator (specs/timing.md §1–§8).

Hypothesis draws random *DSL text* — timers (some with a fixed phase), sporadic sources, data triggers
with prescalers, AND/OR compounds, cooperative siblings, several cores, connection delays, explicit
deadlines, user response-time bounds (promises kept: at least the computed WCRT) and chains — so the
whole pipeline
(parse → resolve → validate → model → analysis) is exercised. For each system the simulator runs
random scenarios (phases, execution times in [bcet, wcet], delays, counter phases) plus one where every
job takes its wcet and every message its largest delay. No simulated response time, activation
distance, reaction time or data age may exceed the analytic worst case or undercut the best case.
The tightness (simulated worst / bound) is collected and printed in the test summary.
"""
from __future__ import annotations

import random
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, find, given, settings
from hypothesis import strategies as st

import verify
from verify.model.arrivals import with_arrivals
from verify.prove.sim import Scenario, chain_latencies, random_scenario, simulate
from verify.timing import analyze

from .test_timing import KINDS, MS, bound_violations, promised_user_bounds

PERIODS_MS = [10, 20, 25, 40, 50, 100]
TIGHTNESS: dict[str, list[Fraction]] = {kind: [] for kind in KINDS}


@st.composite
def systems(draw, arrivals: bool = False) -> str:
    """A random, valid system as DSL text: one component per task (plus cooperative siblings), with
    fixed timer phases, explicit deadlines and user response-time bounds drawn sometimes. A user
    bound is a promise, so it is drawn as the computed WCRT plus a slack (``promised_user_bounds``).
    With ``arrivals``, the system declares an ``arrival_cost`` (specs/timing.md §6.6)."""
    n = draw(st.integers(2, 6))
    cores = draw(st.integers(1, 2))
    components, bindings, connections, chains = [], [], [], []
    slack: dict[str, Fraction | None] = {}  # user-bound slack over the computed WCRT (ms), per task
    producers: list[int] = []  # tasks whose out-port `o` exists
    edges: dict[int, list[int]] = {}
    for i in range(n):
        reads, ins, extra, act = [], [], [], None
        if i == 0 or draw(st.booleans()):
            period = draw(st.sampled_from(PERIODS_MS))
            if draw(st.integers(0, 3)) == 0:
                act = f"sporadic {period} ms .. {period * draw(st.integers(4, 8)) / 4} ms"
            else:
                act = f"timer {period} ms" + _phase(draw, period)
        else:
            mode = draw(st.sampled_from(["single", "single", "and", "or"]))
            k = draw(st.sampled_from([1, 1, 2, 3]))
            members = ["a"] if mode == "single" else ["a", "b"]
            for m in members:
                w = draw(st.integers(0, i - 1))
                ins.append(m)
                reads.append(m)
                connections.append((w, i, m))
                edges.setdefault(w, []).append(i)
            port = "a" if mode == "single" else "ab"
            if mode != "single":
                extra.append(f"  in ab = a {'&' if mode == 'and' else '|'} b")
            act = f"trigger {port}" + (f" every {k}" if k > 1 else "")
        if i > 0 and draw(st.booleans()):
            w = draw(st.integers(0, i - 1))
            ins.append("r")
            reads.append("r")
            connections.append((w, i, "r"))
            edges.setdefault(w, []).append(i)
        wcet = Fraction(draw(st.integers(1, 8)), draw(st.sampled_from([1, 2, 4])))
        bcet = wcet * Fraction(draw(st.integers(0, 4)), 4)
        coop = draw(st.integers(0, 3)) == 0
        sibling = coop and draw(st.booleans())
        lines = [f"component C{i} {{"] + [f"  in {p} : T" for p in ins] + ["  out o : T"] + extra
        lines += [f"  task T{'' if not coop else ' cooperative'} {{"] + [f"    reads {r}" for r in reads]
        lines += ["    produces o", f"    bcet {_ms(bcet)}", f"    wcet {_ms(wcet)}", "  }"]
        if sibling:
            lines += ["  task S cooperative {", f"    wcet {_ms(wcet / 2)}", "  }"]
        lines.append("}")
        components.append("\n".join(lines))
        core = draw(st.integers(0, cores - 1))
        deadline = draw(st.sampled_from([None] * 8 + [10, 25, 50, 100, 200, 400]))
        body = [f"    task T priority {draw(st.integers(1, 8))} {act}"
                + (f" deadline {deadline} ms" if deadline else "") + f"@wcrt:i{i}.T@"]
        slack_choices = st.sampled_from([None, None, None, Fraction(0), Fraction(0), Fraction(1, 2), Fraction(5)])
        slack[f"i{i}.T"] = draw(slack_choices)
        if sibling:
            sib_core = draw(st.integers(0, cores - 1))
            sib_period = draw(st.sampled_from(PERIODS_MS))
            body.append(f"    task S priority {draw(st.integers(1, 8))} on c{sib_core} "
                        f"timer {sib_period} ms{_phase(draw, sib_period)}@wcrt:i{i}.S@")
            slack[f"i{i}.S"] = draw(slack_choices)
        bindings.append(f"  instance i{i} : C{i} on c{core} {{\n" + "\n".join(body) + "\n  }")
        producers.append(i)
    conn_lines = []
    for w, r, port in connections:
        dmin = draw(st.sampled_from([0, 0, 1, 2]))
        dmax = dmin + draw(st.sampled_from([0, 0, 1, 3]))
        delay = "" if dmax == 0 else f" delay {dmin} ms .. {dmax} ms"
        conn_lines.append(f"  connect i{w}.o -> i{r}.{port}{delay}")
    for c in range(draw(st.integers(1, 3))):
        path = [draw(st.integers(0, n - 1))]
        while len(path) < 5 and path[-1] in edges and draw(st.integers(0, 4)) > 0:
            nxt = draw(st.sampled_from(sorted(set(edges[path[-1]]))))
            if nxt in path:
                break
            path.append(nxt)
        chains.append(f"  chain ch{c}: " + " -> ".join(f"i{t}.o" for t in path))
    cost = [f"  arrival_cost {_ms(Fraction(draw(st.integers(1, 8)), 4))}"] if arrivals else []
    system = ["system S {"] + [f"  core c{c}" for c in range(cores)] + cost + bindings + conn_lines + chains + ["}"]
    template = "\n\n".join(components) + "\n\n" + "\n".join(system) + "\n"

    def render(bounds: dict[str, Fraction]) -> str:
        text = template
        for tid in slack:
            text = text.replace(f"@wcrt:{tid}@", f" wcrt {_ms(bounds[tid] / MS)}" if tid in bounds else "")
        return text

    def build(bounds: dict[str, Fraction]):
        result = verify.load_text(render(bounds), "random.vfy")
        assert result.ok, [(d.code, d.message) for d in result.diagnostics] + [render(bounds)]
        return result.system()

    chosen = {tid: extra * MS for tid, extra in slack.items() if extra is not None}
    return render(promised_user_bounds(build, chosen)[1])


def _phase(draw, period: int) -> str:
    """Sometimes a fixed phase in [0, period), in half milliseconds (else the phase is unknown)."""
    if not draw(st.booleans()):
        return ""
    return f" phase {_ms(Fraction(draw(st.integers(0, 2 * period - 1)), 2))}"


def _ms(value: Fraction) -> str:
    return f"{value.numerator}/{value.denominator} ms" if value.denominator != 1 else f"{value.numerator} ms"


def _slowest(scenario: Scenario, model) -> Scenario:
    def delay(src, dst, _i):
        return next(lk.delay_max for lk in model.links if (lk.source, lk.target) == (src, dst))

    return Scenario(scenario.horizon, scenario.phases, None, delay, None, scenario.counter_phase)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(systems(), st.integers(0, 2**16))
def test_no_simulated_latency_beyond_the_analytic_bounds(text, seed):
    _runs_within_the_bounds(text, seed, 4)


def _runs_within_the_bounds(text: str, seed: int, runs: int, transform=lambda model: model) -> None:
    """``runs`` simulated runs of 2 s of the system ``text`` (``transform``ed; the first with every job at
    its wcet) exceed none of its analytic bounds; their tightness recorded."""
    result = verify.load_text(text, "random.vfy")
    assert result.ok, [(d.code, d.message) for d in result.diagnostics] + [text]
    model = transform(result.system())
    analysis = analyze(model)
    for run in range(runs):
        scenario = random_scenario(model, random.Random(f"{seed}/{run}"), Fraction(2))
        if run == 0:
            scenario = _slowest(scenario, model)
        trace = simulate(model, scenario)
        assert bound_violations(model, trace, analysis) == [], text
        _record_tightness(model, analysis, trace)


@pytest.mark.slow
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(systems(arrivals=True), st.integers(0, 2**16))
def test_no_simulated_latency_beyond_the_analytic_bounds_with_arrivals(text, seed):
    """The same with an arrival cost: the simulators run the arrival tasks (``with_arrivals``) the
    analysis charges (specs/timing.md §6.6)."""
    _runs_within_the_bounds(text, seed, 3, with_arrivals)


@pytest.mark.slow
def test_the_generator_draws_phases_deadlines_and_user_bounds():
    """The rules for fixed phases (§3, §5.2 `F = φ`), explicit deadlines (§6.2) and user bounds (rule
    "user bound") are drawn, together, by the generator above."""
    text = find(systems(), lambda t: " phase " in t and " deadline " in t and " wcrt " in t,
                settings=settings(max_examples=500, deadline=None, database=None,
                                  suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large]))
    assert verify.load_text(text, "random.vfy").ok


@pytest.mark.slow
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(systems())
def test_generated_user_bounds_are_kept_promises(text):
    """Every drawn user bound is at least the WCRT computed with all bounds in place (and so at
    least the wcet: no E315)."""
    model = verify.load_text(text, "random.vfy").system()
    analysis = analyze(model)
    for t in model.tasks:
        if t.wcrt_bound is not None:
            computed = analysis.task(t.id).response.wcrt_computed
            assert computed is not None and t.wcet <= computed <= t.wcrt_bound == analysis.task(t.id).wcrt, text


def _record_tightness(model, analysis, trace) -> None:
    for chain in model.chains:
        bounds, observed = analysis.chain(chain.name), chain_latencies(trace, chain)
        for kind in KINDS:
            bound, worst = bounds.bound(kind).worst, observed.worst(kind)
            if bound and worst is not None:
                TIGHTNESS[kind].append(worst.value / bound)


def tightness_summary() -> list[str]:
    """Lines for the pytest summary: how close the simulator came to each bound."""
    lines = []
    for kind, ratios in TIGHTNESS.items():
        if ratios:
            ordered = sorted(ratios)
            median = ordered[len(ordered) // 2]
            lines.append(f"{kind:28s} samples {len(ratios):4d}  max {float(ordered[-1]):.3f}  "
                         f"median {float(median):.3f}  (simulated worst / analytic bound)")
    return lines
