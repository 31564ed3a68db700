"""Hand-checked analysis results on the navigation example (specs/timing.md §5–§7).

Derivations (all on the configured examples/navigation/navigation.vfy; times in ms):

cpu0 — PoseUpdateTask (prio 10, C 0.1..0.15, timer 100), RobotTask (prio 9, C 0.2..0.5, triggered
by navvel at 20 Hz), LaserTask (prio 8, C 1..2, timer 25): R(Pose) = 0.15, R(Robot) = 0.5 + 0.15 =
0.65, R(Laser) = 2 + 0.15 + 0.5 = 2.65 (§6.2, one job each).

cpu1 — OATask (prio 5, C 2..8, timer 50, the only cooperative task of `oa`: no blocking), PlannerTask
(prio 3, C 30..80, triggered by map), CurMapTask (prio 2, C 20..60, triggered by every 10th scan).
- Event models (§5.2). Scans reach the Mapper with output jitter X = (R − B)(Laser) + (d⁺ − d⁻) =
  1.65 + 0.5 = 2.15; prescaler 10: P = 10·25 = 250, J = 2.15, so A⁺(Mapper) = 252.15 and A⁻ =
  247.85. The Planner's arrivals carry the Mapper's jitter plus its X = (172 − 20) + 0:
  P = 250, J = 2.15 + 152 = 154.15, so A⁺(Planner) = 404.15 and A⁻ = 250 − 154.15 = 95.85.
- R(OA) = 8 (highest priority on cpu1).
- R(Mapper), §6.2 with the causal cap: the Planner is only released by the Mapper's completions
  (L⁺ = d⁺ = 0), N = ⌊(0 + J⁻ 2.15 + R 172 − B 20)/250⌋ + 1 = 1, so cap(1) = 1 Planner job (without
  the cap its jitter would admit 2, and R = 268 > A⁺). w = 60 + 1·80 + ⌈w/50⌉·8:
  60 → 156 → 172 → 172. δ⁻(2) = 247.85 ≥ 172, so one job: R(Mapper) = 172.
- R(Planner): w(1) = 80 + ⌈w/50⌉·8 = 96 > δ⁻(2) = 95.85, so a second job: w(2) = 160 + ⌈w/50⌉·8
  = 192 ≤ δ⁻(3) = 345.85. R = max(96 − 0, 192 − 95.85) = 96.15 (busy window, 2 jobs).

Mapper: 40 Hz / 10 = 4 Hz.

Reactive chain PoseUpdate → Laser → OA → Robot. The hop PoseUpdate → Laser qualifies for the
same-core priority rule (§7.6: both on cpu0, priority 10 > 8, no delay, PoseUpdate preemptive):
  reaction                                                          data age (reduced)
  W⁺(Pose) 100 + R(Pose) 0.15           = 100.15  first-task          —
  W⁺(Laser) 25 + R(Laser) 2.65 − R(Pose) 0.15 = 27.5  (7.6b)          A⁺(Pose) 100        (7.6a)
  d⁺ 1 + W⁺(OA) 50 + R(OA) 8            =  59     register            1 + A⁺(Laser) 25 + 2.65 = 28.65
  d⁺ 2 + δ⁺(OA, 1) 0 + R(Robot) 0.65    =   2.65  data trigger k=1    d⁺ 2 + R(OA) 8 = 10
  —                                                                   R(Robot) 0.65
  = 189.3 (margin 60.7 to 250; register rule alone: 189.45)           = 139.3 (margin 60.7 to 200)
Non-reduced data age: + A⁺(Pose) 100 = 239.3. Best: Σ bcet + Σ d⁻ = 0.1 + 1 + 2 + 0.2 + 0.5 + 1 = 4.8.

Planning chain Laser → Mapper → Planner → OA (no hop qualifies for §7.6: Laser → Mapper crosses
cores, and on cpu1 the readers have the higher priorities):
  W⁺(Laser) 25 + R(Laser) 2.65                       =  27.65  first-task sampling
  d⁺ 1 + δ⁺(Laser, 10) + R(Mapper) 172                = 399.65  data trigger prescaler 10, with
      δ⁺(Laser, 10) = 9·25 + J⁺ 0 + (R − B)(Laser) 1.65 = 226.65 (the register rule would give
      1 + W⁺(Mapper) 255.8 + 172 = 428.8)
  d⁺ 0 + δ⁺(Mapper, 1) 0 + R(Planner) 96.15          =  96.15  data trigger k=1
  d⁺ 0 + W⁺(OA) 50 + R(OA) 8                         =  58     register sampling
  reaction time = 581.45 (margin 418.55 to 1 s).
Data age: (d⁺ 1 + R(Laser) 2.65) + (0 + R(Mapper) 172) + (0 + A⁺(Planner) 404.15 + R(Planner)
96.15) + R(OA) 8 = 3.65 + 172 + 500.3 + 8 = 683.95 reduced; + A⁺(Laser) 25 = 708.95 non-reduced.
Best: 1 + (0.5 + 20) + (0 + 30) + (0 + 2) = 53.5; non-reduced adds τ₁'s least read gap
max(C⁻ 1, A⁻ 25 − (R − C⁻) 1.65) = 23.35: 76.85.
"""
from __future__ import annotations

from fractions import Fraction

import verify
from verify.timing import analyze, diagnostics_of
from verify.timing.chains import REGISTER, SAME_CORE

from .conftest import EXAMPLES

MS = Fraction(1, 1000)


def ms(text: str) -> Fraction:
    return Fraction(text) * MS


def _analysis(**kwargs):
    return analyze(verify.load(str(EXAMPLES / "navigation" / "navigation.vfy")).system(), **kwargs)


def test_response_times_on_cpu0():
    result = _analysis()
    assert result.task("laser.LaserTask").wcrt == ms("2.65")
    assert result.task("base.RobotTask").wcrt == ms("0.65")
    assert result.task("base.PoseUpdateTask").wcrt == ms("0.15")


def test_event_models_and_response_times_on_cpu1():
    result = _analysis()
    mapper, planner, oa = (result.task(t) for t in ("mapper.CurMapTask", "planner.PlannerTask", "oa.OATask"))
    assert (mapper.events.period_max, mapper.events.jitter_max) == (ms("250"), ms("2.15"))
    assert (mapper.a_max, mapper.a_min) == (ms("252.15"), ms("247.85"))
    assert (planner.events.period_min, planner.events.jitter_min) == (ms("250"), ms("154.15"))
    assert (planner.a_max, planner.a_min) == (ms("404.15"), ms("95.85"))
    assert oa.wcrt == ms("8") and oa.response.blocking in (None, 0)
    assert mapper.wcrt == ms("172") and mapper.response.busy_jobs == 1
    assert planner.wcrt == ms("96.15")
    assert (planner.response.busy_jobs, planner.response.critical_job) == (2, 2)
    assert mapper.wcrt <= mapper.response.deadline == ms("252.15")


def test_mapper_runs_at_four_hertz():
    rate = _analysis().task("mapper.CurMapTask").rate
    assert (rate.low, rate.high) == (Fraction(4), Fraction(4))


def test_reactive_chain_by_hand():
    result = _analysis()
    chain = result.chain("reactive")
    pose_laser = chain.steps[1]
    assert (pose_laser.reaction.rule, pose_laser.data_age.rule) == (SAME_CORE, SAME_CORE)
    assert (pose_laser.reaction.value, pose_laser.data_age.value) == (ms("27.5"), ms("100"))
    assert [s.reaction.rule for s in chain.steps[2:4]] == [REGISTER, "data trigger k=1"]
    assert [s.reaction.value for s in chain.steps[:4]] == [ms("100.15"), ms("27.5"), ms("59"), ms("2.65")]
    assert [s.data_age.value for s in chain.steps[1:]] == [ms("100"), ms("28.65"), ms("10"), ms("0.65")]
    assert chain.bound("reaction_time").worst == ms("189.3")
    assert chain.bound("reaction_time_reduced").worst == ms("89.3")
    assert chain.bound("data_age").worst == ms("139.3")
    assert chain.bound("data_age_nonreduced").worst == ms("239.3")
    assert chain.bound("reaction_time").best == ms("4.8")
    assert {s.kind: s.margin for s in chain.specs} == {"reaction_time": ms("60.7"), "data_age": ms("60.7")}
    assert not diagnostics_of(result)


def test_planning_chain_by_hand():
    chain = _analysis().chain("planning")
    laser_mapper = chain.steps[1]
    assert laser_mapper.reaction.rule == "data trigger prescaler k=10"
    assert dict(laser_mapper.reaction.parts)["δ⁺(laser.LaserTask, 10)"] == ms("226.65")
    assert [s.reaction.value for s in chain.steps[:4]] == [ms("27.65"), ms("399.65"), ms("96.15"), ms("58")]
    assert [s.data_age.value for s in chain.steps[1:]] == [ms("3.65"), ms("172"), ms("500.3"), ms("8")]
    assert SAME_CORE not in {s.reaction.rule for s in chain.steps[1:4]} | {s.data_age.rule for s in chain.steps[1:]}
    assert chain.bound("reaction_time").worst == ms("581.45")
    assert chain.bound("data_age").worst == ms("683.95")
    assert chain.bound("data_age_nonreduced").worst == ms("708.95")
    assert chain.steps[0].data_age_non_reduced.value == ms("25")
    assert chain.bound("reaction_time").best == chain.bound("data_age").best == ms("53.5")
    assert chain.bound("data_age_nonreduced").best == ms("76.85")
    assert chain.specs[0].margin == ms("418.55")
    non_reduced = _analysis(data_age="non-reduced").chain("planning")
    assert non_reduced.data_age.worst == ms("708.95")
    assert non_reduced.steps[non_reduced.dominating_age].label == "planner.PlannerTask → oa.OATask"
