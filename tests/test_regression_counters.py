"""Deterministic counters of a few fixed instances against recorded values (issue 38).

Wall-clock times belong to the benchmark harness (``benchmarks/``); the suite checks what the tools
count deterministically for one set of versions (``z3-solver==4.13.4.0``: its resource units are
deterministic for one release, README): Z3 resource units and solver calls of ``synth``, and the
same for further rows (scenarios, fixed-point rounds) as they are added. Each row of ``ROWS`` names
an instance, what is measured on it, and the recorded counters. A counter more than ``FACTOR`` times
its recorded value fails — a change like ``e1a12dc`` (the 500-task ``synth-optimum`` of the
benchmarks went from a proven optimum in 16.6 M resource units to undecided at the default 50 M; at
200 tasks from 1.2 M to 8.2 M units) is caught the day it lands — and so does one below its record
by as much: the record is then out of date (write the new value here, and the benchmark row in
``benchmarks/README.md`` with it).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

import pytest

import verify

from .conftest import EXAMPLES

FACTOR = Fraction(3, 2)


def _waters_holes(n: int, seed: int) -> verify.LoadResult:
    """The instance of the benchmarks' synthesis stages (``hole_share`` 1/5, one chain per five tasks)."""
    from benchmarks.generate import generate_system

    return verify.load_text(generate_system(n, seed, hole_share=Fraction(1, 5), chains=n // 5), f"waters-{n}.vfy")


def synth_optimum(load: Callable[[], verify.LoadResult]) -> Callable[[], dict[str, int]]:
    """``synthesize`` with the default objective and budget: it must prove the optimum."""
    def measure() -> dict[str, int]:
        from verify.synth import synthesize

        result = synthesize(load())
        assert (result.status, result.optimal) == ("sat", True), (result.status, result.reason)
        return {"rlimit": result.stats["rlimit_used"], "solver calls": result.stats["solver_calls"]}
    return measure


@dataclass(frozen=True)
class Row:
    name: str
    measure: Callable[[], dict[str, int]]
    recorded: dict[str, int]
    slow: bool = False


ROWS = (
    Row("synth-optimum navigation-holes", synth_optimum(lambda: verify.load(str(EXAMPLES / "navigation"
                                                                               / "navigation-holes.vfy"))),
        {"rlimit": 1_748_368, "solver calls": 9}),
    Row("synth-optimum waters-200-s1", synth_optimum(lambda: _waters_holes(200, 1)),
        {"rlimit": 3_233_391, "solver calls": 11}, slow=True),
    Row("synth-optimum waters-500-s1", synth_optimum(lambda: _waters_holes(500, 1)),
        {"rlimit": 24_585_321, "solver calls": 13}, slow=True),
)


@pytest.mark.parametrize("row", [pytest.param(r, id=r.name, marks=[pytest.mark.slow] if r.slow else [])
                                 for r in ROWS])
def test_counters_stay_at_their_recorded_values(row: Row):
    measured = row.measure()
    assert set(measured) == set(row.recorded)
    for counter, recorded in row.recorded.items():
        value = measured[counter]
        assert value <= recorded * FACTOR, (f"{row.name}: {counter} {value} is more than {FACTOR} times the "
                                            f"recorded {recorded}: a regression?")
        assert value * FACTOR >= recorded, (f"{row.name}: {counter} {value} is far below the recorded {recorded}: "
                                            "record the new value (and the benchmark row)")
