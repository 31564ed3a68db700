"""Tightness stage: how close the analysis' bounds come to what runs show (issue 16).

``tightness`` draws systems of every shape the property tests draw — timers (some phased), sporadic
sources, data triggers with prescalers, AND and OR compounds, cooperative siblings, one or two cores,
equal and distinct priorities, connection delays, deadlines, user bounds
(``tests/test_bounds_vs_simulation.systems``, derandomized: the same systems on every run) — and the
AND-join shape of ``tests/test_and_joins`` (one core, an AND of two equal-period timers, a trigger
chain behind it with a prescaler, a sporadic source, priorities from a small set, seeded), and the
Autoware reference-system example (examples/autoware-reference; N/2 scenarios). Each is analysed and
simulated (four scenarios of 2 s, one of them every job at its wcet and every message at its largest
delay). It reports, per latency metric: the share of chains with a bound, and over the
bounded ones the mean and the minimum of simulated worst / bound; and the share of systems with E312
(some task without a response-time bound within its deadline: the drawn systems have explicit
deadlines, which a run may really miss, besides the implicit ones, A⁺).
"""
from __future__ import annotations

import random
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


def measure(models: list, runs: int = 4) -> dict[str, object]:
    from verify.sim import Scenario, chain_latencies, random_scenario, simulate
    from verify.timing import analyze, diagnostics_of

    ratios: dict[str, list[Fraction]] = {m: [] for m in METRICS}
    chains = {m: 0 for m in METRICS}
    bounded = {m: 0 for m in METRICS}
    e312 = 0
    for n, model in enumerate(models):
        analysis = analyze(model)
        if any(d.code == "E312" for d in diagnostics_of(analysis)):
            e312 += 1
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
        for chain in model.chains:
            bounds = analysis.chain(chain.name)
            for metric in METRICS:
                chains[metric] += 1
                bound = bounds.bound(metric).worst
                if bound is not None:
                    bounded[metric] += 1
                    if bound > 0 and (chain.name, metric) in worst:
                        ratios[metric].append(worst[(chain.name, metric)] / bound)
    result: dict[str, object] = {"systems": len(models), "with E312": f"{e312} ({e312 / len(models):.0%})"}
    for metric in METRICS:
        r = ratios[metric]
        result[metric] = (f"bounded {bounded[metric]}/{chains[metric]}, simulated/bound mean "
                          f"{float(statistics.fmean(r)):.3f} min {float(min(r)):.3f}" if r else "no sample")
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
           "systems of each kind)", sizes=(60,), quick_sizes=(4,), generator=generated)
    def tightness(inst) -> dict:
        count = inst.n_tasks
        import verify

        random_result = measure(_models(_random_systems(count)))
        and_result = measure(_models(_and_systems(count)))
        autoware = verify.load(str(AUTOWARE)).system()
        autoware_result = measure([autoware], runs=max(4, count // 2))
        del autoware_result["systems"]
        return {**{f"random {k}": v for k, v in random_result.items()},
                **{f"AND {k}": v for k, v in and_result.items()},
                **{f"Autoware {k}": v for k, v in autoware_result.items()}}
