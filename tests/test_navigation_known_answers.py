"""Hand-checked analysis results on the navigation example (specs/timing.md §6–§7).

Derivations (all on the configured examples/navigation/navigation.vfy):
- cpu0 holds PoseUpdateTask (prio 10, 150 us / 100 ms), RobotTask (prio 9, 500 us, triggered by
  navvel at 20 Hz) and LaserTask (prio 8, 2 ms / 25 ms): R(Laser) = 2 + 0.15 + 0.5 = 2.65 ms,
  R(Robot) = 0.5 + 0.15 = 0.65 ms.
- Mapper: 40 Hz / 10 = 4 Hz.
- Reactive chain PoseUpdate → Laser → OA → Robot, reaction time (§7):
  W⁺(Pose) 100 + R(Pose) 0.15                      = 100.15 ms  (first-task sampling)
  + d⁺ 0 + W⁺(Laser) 25 + R(Laser) 2.65             =  27.65 ms  (register, Davare)
  + d⁺ 1 + W⁺(OA) 50 + R(OA) 8                      =  59    ms  (register, Davare)
  + d⁺ 2 + δ⁺(OA, 1) 0 + R(Robot) 0.65              =   2.65 ms  (data trigger k = 1)
  = 189.45 ms against the 250 ms spec: margin 60.55 ms.
- Its reduced data age: (0 + 100 + 0.15) + (1 + 25 + 2.65) + (2 + 8) + 0.65 = 139.45 ms.
- Best case: Σ bcet + Σ d⁻ = 0.1 + 1 + 2 + 0.2 + 0.5 + 1 = 4.8 ms.
"""
from __future__ import annotations

from fractions import Fraction

import verify
from verify.timing import analyze, diagnostics_of

from .conftest import EXAMPLES

MS = Fraction(1, 1000)


def _analysis():
    return analyze(verify.load(str(EXAMPLES / "navigation" / "navigation.vfy")).system())


def test_response_times_on_cpu0():
    result = _analysis()
    assert result.task("laser.LaserTask").wcrt == Fraction(265, 100) * MS
    assert result.task("base.RobotTask").wcrt == Fraction(65, 100) * MS
    assert result.task("base.PoseUpdateTask").wcrt == Fraction(15, 100) * MS


def test_mapper_runs_at_four_hertz():
    rate = _analysis().task("mapper.CurMapTask").rate
    assert (rate.low, rate.high) == (Fraction(4), Fraction(4))


def test_reactive_chain_by_hand():
    result = _analysis()
    chain = result.chain("reactive")
    assert chain.bound("reaction_time").worst == Fraction(18945, 100) * MS
    assert chain.bound("data_age").worst == Fraction(13945, 100) * MS
    assert chain.bound("reaction_time").best == Fraction(48, 10) * MS
    assert not diagnostics_of(result)
