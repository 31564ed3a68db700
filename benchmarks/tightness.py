"""Tightness stage: how close the analysis' bounds come to what runs show (issue 16).

``tightness`` draws systems of every shape the property tests draw — timers (some phased), sporadic
sources, data triggers with prescalers, AND and OR compounds, cooperative siblings, one or two cores,
equal and distinct priorities, connection delays, deadlines, user bounds
(``tests/test_bounds_vs_simulation.systems``, derandomized: the same systems on every run; also
measured with their user bounds removed, ``_without_user_bounds``) — and the
AND-join shape of ``tests/test_and_joins`` (one core, an AND of two equal-period timers, a trigger
chain behind it with a prescaler, a sporadic source, priorities from a small set, seeded), and the
Autoware reference-system example (examples/autoware-reference; N/2 scenarios). Each is analysed and
simulated (four scenarios of 2 s, one of them every job at its wcet and every message at its largest
delay), and measured by ``prove``'s own methods (``_found_by_prove``: the exact enumeration where the
system is in its exact class, else its falsifying search with every goal at the bound, 200 scenarios
per system and 1,000 for the Autoware example, seeded per system): the worst run of a chain is the
larger of the two (issue 16 measures against "worst simulated or found by prove"). It reports, per
latency metric: the share of chains with a bound, and over the bounded ones the mean and the minimum
of worst run / bound (and of the simulated worst alone / bound); and the share of systems with E312
(some task without any response-time bound: specs/timing.md §6.2; a bound above a deadline is E316,
not counted). A run above its bound is a
soundness bug: the stage stops with an error row (``AboveBound``) instead of a ratio above 1.
"""
from __future__ import annotations

import random
import re
import statistics
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

METRICS = ("reaction_time", "data_age")
AUTOWARE = Path(__file__).resolve().parent.parent / "examples" / "autoware-reference" / "autoware.vfy"


def _random_systems(count: int) -> list[str]:
    from hypothesis import HealthCheck, given, settings

    from tests.test_bounds_vs_simulation import systems

    drawn: list[str] = []

    @settings(derandomize=True, database=None, max_examples=count, deadline=None,
              suppress_health_check=list(HealthCheck))
    @given(systems())
    def collect(text: str) -> None:
        drawn.append(text)

    collect()
    return drawn[:count]


def _without_user_bounds(texts: list[str]) -> list[str]:
    """The same systems with every user bound (``wcrt`` in a binding) removed. The generator draws them
    above the computed WCRT, as promises the model cannot show: a user bound replaces the computed
    WCRT everywhere (specs/timing.md §6.2), and no run of the model reaches it. Without them the
    bounds are the analysis' own."""
    return [re.sub(r" wcrt [0-9/]+ ms", "", text) for text in texts]


def _and_systems(count: int) -> list[str]:
    from tests.test_and_joins import shaped

    rng = random.Random(16)
    texts = []
    for _ in range(count):
        texts.append(shaped(rng.choice([5, 10]), rng.choice([20, 40]), rng.choice([1, 2, 3]),
                            [rng.choice([100, 200, 400, 600, 800, 1000]) for _ in range(7)],
                            [rng.choice([1, 2, 4]) for _ in range(7)], [rng.choice([2, 5, 7, 8]) for _ in range(7)]))
    return texts


def _models(texts: list[str]) -> list[object]:
    import verify

    return [verify.load_text(text, "tight.vfy").system() for text in texts]


#: scenarios of prove's falsifying search per system (``verify.prove.exact.search``), and for the Autoware example
SEARCH_BUDGET = 200
AUTOWARE_SEARCH_BUDGET = 1000
#: both of them with ``--quick`` (parameters ``budget`` and ``autoware_budget``): the smoke test checks that
#: every part of the stage runs and no run is above its bound, not how close the searches come
QUICK_SEARCH_BUDGET = 20


class AboveBound(AssertionError):
    """A run above an analytic bound: a soundness bug of the analysis (or of the simulator)."""


def _simulated(model, n: int, runs: int) -> dict[tuple[str, str], Fraction]:
    """The worst sample per (chain, metric) over ``runs`` random scenarios of 2 s, the first with every job
    at its wcet and every message at its largest delay."""
    from verify.prove.sim import Scenario, chain_latencies, random_scenario, simulate

    worst: dict[tuple[str, str], Fraction] = {}
    for run in range(runs):
        scenario = random_scenario(model, random.Random(f"{n}/{run}"), Fraction(2))
        if run == 0:  # every job at its wcet, every message at its largest delay
            delays = {(lk.source, lk.target): lk.delay_max for lk in model.links}
            scenario = Scenario(scenario.horizon, scenario.phases, None,
                                lambda src, dst, _i, d=delays: d[(src, dst)], None, scenario.counter_phase)
        trace = simulate(model, scenario)
        for chain in model.chains:
            observed = chain_latencies(trace, chain)
            for metric in METRICS:
                sample = observed.worst(metric)
                if sample is not None:
                    key = (chain.name, metric)
                    worst[key] = max(worst.get(key, Fraction(0)), sample.value)
    return worst


def _found_by_prove(model, bounds: dict[tuple[str, str], Fraction], n: int, budget: int
                    ) -> dict[tuple[str, str], Fraction]:
    """The worst sample per (chain, metric) that ``prove``'s own methods find: the exact supremum where the
    system is in the exact class and its representatives fit in ``budget`` (specs/proof.md §4), else the
    falsifying search (§6) with ``budget`` scenarios, each goal set at the bound (so it never stops early
    unless it refutes a bound), seeded per system."""
    from verify.prove.exact import Budget, Goal, enumerate_exact, search, search_horizon
    from verify.prove.scenario import Target

    targets = {Target(metric, chain): (chain, metric) for (chain, metric) in bounds}
    if not targets:
        return {}
    found: dict[tuple[str, str], Fraction] = {}
    exact = enumerate_exact(model, sorted(targets), Budget(budget), jobs=1)
    if exact is not None and exact.complete:
        for target, key in targets.items():
            value = exact.worst[target].value
            if value is not None:
                found[key] = value
        return found
    goals = [Goal(target, above=bounds[key]) for target, key in sorted(targets.items())]
    result = search(model, goals, Budget(budget), search_horizon(model, None), seed=f"tightness/{n}")
    for target, key in targets.items():
        measured = result.worst.get(target)
        sample = None if measured is None else measured.values[target].worst
        if sample is not None:
            found[key] = sample.value
    return found


def measure(models: list, runs: int = 4, budget: int = SEARCH_BUDGET) -> dict[str, object]:
    """Per metric: chains bounded, and the mean and minimum of (worst run) / bound, the worst run being the
    larger of the simulated worst and the worst that ``prove`` finds (``_found_by_prove``); the simulation
    alone is reported beside it. Raises ``AboveBound`` on a run above its bound."""
    from verify.timing import analyze, diagnostics_of

    ratios: dict[str, list[Fraction]] = {m: [] for m in METRICS}
    simulated: dict[str, list[Fraction]] = {m: [] for m in METRICS}
    chains = {m: 0 for m in METRICS}
    bounded = {m: 0 for m in METRICS}
    e312 = 0
    for n, model in enumerate(models):
        analysis = analyze(model)
        if any(d.code == "E312" for d in diagnostics_of(analysis)):
            e312 += 1
        bounds: dict[tuple[str, str], Fraction] = {}
        for chain in model.chains:
            for metric in METRICS:
                chains[metric] += 1
                bound = analysis.chain(chain.name).bound(metric).worst
                if bound is not None:
                    bounded[metric] += 1
                    bounds[(chain.name, metric)] = bound
        sim = _simulated(model, n, runs)
        found = _found_by_prove(model, bounds, n, budget) if budget else {}
        for key, bound in bounds.items():
            worst = max([x for x in (sim.get(key), found.get(key)) if x is not None], default=None)
            if worst is not None and worst > bound:
                raise AboveBound(f"system {n}, chain {key[0]}: a run reaches {key[1]} {worst} above the bound {bound} "
                                 f"(simulated {sim.get(key)}, found by prove {found.get(key)})")
            if bound > 0 and worst is not None:
                ratios[key[1]].append(worst / bound)
                if key in sim:
                    simulated[key[1]].append(sim[key] / bound)
    result: dict[str, object] = {"systems": len(models), "with E312": f"{e312} ({e312 / len(models):.0%})"}
    for metric in METRICS:
        r, s = ratios[metric], simulated[metric]
        result[metric] = (f"bounded {bounded[metric]}/{chains[metric]}, worst run / bound mean "
                          f"{float(statistics.fmean(r)):.3f} min {float(min(r)):.3f}"
                          + (f" (simulated alone: mean {float(statistics.fmean(s)):.3f} min {float(min(s)):.3f})"
                             if s else "") if r else "no sample")
    return result


def register(stage: Callable[..., Callable], error: type[Exception], unavailable: dict[str, str]) -> None:
    try:
        import hypothesis  # noqa: F401
    except ImportError as err:
        unavailable["tightness"] = f"hypothesis is not installed ({err})"
        return

    def generated(n_tasks: int, seed: int, **_: object) -> str:
        """The first system of the AND-join shape (the row's lines and chains); the stage draws its own."""
        return _and_systems(1)[0]

    @stage("tightness", "analysis against simulation on drawn systems of every shape (the property tests' "
           "generator, derandomized) and of the AND-join shape: per metric the share of chains bounded, mean and "
           "minimum of simulated worst / bound, and the share of systems with E312 (the size is the number of "
           "systems of each kind)", sizes=(60,), quick_sizes=(4,), generator=generated,
           params={"budget": SEARCH_BUDGET, "autoware_budget": AUTOWARE_SEARCH_BUDGET},
           quick_params={"budget": QUICK_SEARCH_BUDGET, "autoware_budget": QUICK_SEARCH_BUDGET})
    def tightness(inst, budget: int, autoware_budget: int) -> dict:
        count = inst.n_tasks
        import verify

        try:
            drawn = _random_systems(count)
            random_result = measure(_models(drawn), budget=budget)
            own_result = measure(_models(_without_user_bounds(drawn)), budget=budget)
            and_result = measure(_models(_and_systems(count)), budget=budget)
            autoware = verify.load(str(AUTOWARE)).system()
            autoware_result = measure([autoware], runs=max(4, count // 2), budget=autoware_budget)
        except AboveBound as err:  # a soundness bug: an error row, never a ratio above 1
            raise error(f"a run above its analytic bound: {err}") from err
        del autoware_result["systems"]
        del own_result["systems"]
        return {**{f"random {k}": v for k, v in random_result.items()},
                **{f"random without user bounds {k}": v for k, v in own_result.items()},
                **{f"AND {k}": v for k, v in and_result.items()},
                **{f"Autoware {k}": v for k, v in autoware_result.items()}}
