"""The activation kinds' behaviour (verify.model.activations) and integer time (verify.core.timebase)."""
from __future__ import annotations

from fractions import Fraction as F

import pytest
from hypothesis import given
from hypothesis import strategies as st

from verify.model.activations import KINDS, Activation, DataTriggered, Hole, Periodic, SporadicSource
from verify.core.construct import is_plain_frozen
from verify.core.timebase import TimeBase, ceil_to, floor_to, frac_gcd, frac_lcm

MS = F(1, 1000)


def test_every_kind_is_registered_by_its_name_and_built_fast():
    assert {"timer": Periodic, "sporadic": SporadicSource, "trigger": DataTriggered, "hole": Hole} == KINDS
    for name, cls in KINDS.items():
        assert issubclass(cls, Activation) and cls.kind == name
    for cls in (Periodic, SporadicSource, DataTriggered):  # built by the thousand: verify.core.construct's fast path
        assert is_plain_frozen(cls)


def test_a_timer_releases_strictly_periodically_from_its_phase():
    free, fixed = Periodic(10 * MS), Periodic(10 * MS, 3 * MS)
    assert free.gaps == (10 * MS, 10 * MS) and free.strict_period == 10 * MS and not free.irregular
    assert free.fixed_phase is None and free.offset_window == 10 * MS and free.first_release_latest == 10 * MS
    assert fixed.fixed_phase == 3 * MS and fixed.offset_window is None and fixed.first_release_latest == 3 * MS
    assert free.trigger_port is None and free.trigger_members == () and free.release_every == 1
    assert not free.listens_to("scan") and not free.unknown
    assert free.describe() == "timer 10 ms" and free.offset_name == "phase"
    assert free.as_written() == "timer 10 ms" and fixed.as_written() == "timer 10 ms phase 3 ms"
    assert free.timer_callback and free.trigger_mode is None


def test_a_sporadic_source_has_a_gap_range_and_no_hyperperiod():
    act = SporadicSource(5 * MS, 20 * MS)
    assert act.gaps == (5 * MS, 20 * MS) and act.strict_period is None and act.irregular
    assert act.offset_window == 20 * MS and act.first_release_latest == 20 * MS
    assert act.describe() == "sporadic 5 ms .. 20 ms" and act.offset_name == "first release"
    assert act.as_written() == act.describe() and not act.timer_callback and act.trigger_mode is None


@pytest.mark.parametrize("mode, single, every_member", [("single", "scan", False), ("and", None, True),
                                                        ("or", None, False)])
def test_a_data_trigger_listens_to_its_members(mode, single, every_member):
    members = ("scan",) if mode == "single" else ("scan", "odom")
    act = DataTriggered("scan" if mode == "single" else "both", members, mode, 4)
    assert act.gaps is None and act.offset_window is None and act.first_release_latest is None
    assert act.trigger_members == members and act.release_every == 4 and act.all_members == every_member
    assert act.single_port == single and act.trigger_port == ("scan" if mode == "single" else "both")
    assert act.listens_to("scan") and not act.listens_to("goal")
    assert act.trigger_mode == mode and not act.timer_callback
    assert act.as_written() == act.describe() == f"trigger {act.trigger_port} every 4"


def test_a_hole_is_unknown_and_releases_nothing():
    hole = Hole()
    assert hole.unknown and hole.kind == "hole" and hole.gaps is None and hole.trigger_port is None
    assert hole.trigger_mode is None and not hole.timer_callback
    assert hole.as_written() == "activation ?" and hole.describe() == "synthesis hole"


def test_time_bases_are_exact():
    base = TimeBase.gcd_of([10 * MS, F(25, 10000), 0])
    assert base.unit == F(1, 400) and base.ticks(10 * MS) == 4 and base.seconds(4) == 10 * MS
    with pytest.raises(ValueError, match="not a multiple"):
        base.ticks(MS)
    assert TimeBase.gcd_of([0, 0]).unit == 1 and TimeBase.gcd_of([], default=MS).unit == MS
    per = TimeBase.per_second([4, 6])
    assert per.scale == 12 and per.ticks(F(5, 6)) == 10
    with pytest.raises(ValueError):
        TimeBase(F(0))
    with pytest.raises(ValueError):
        _ = TimeBase(F(2, 3)).scale


fractions = st.fractions(min_value=F(1, 10**6), max_value=F(10**3), max_denominator=10**6)


@given(st.lists(fractions, min_size=1, max_size=6))
def test_the_gcd_base_is_the_coarsest_in_which_every_time_is_whole(values):
    base = TimeBase.gcd_of(values)
    assert all(base.whole(v) and base.seconds(base.ticks(v)) == v for v in values)
    for k in (2, 3, 5):  # no coarser base divides them all
        assert not all((v / (base.unit * k)).denominator == 1 for v in values)
    lcm = frac_lcm(values)
    assert all((lcm / v).denominator == 1 for v in values) and frac_gcd(values) == base.unit


@given(fractions, fractions)
def test_rounding_to_a_tick(value, tick):
    assert floor_to(value, tick) <= value <= ceil_to(value, tick)
    assert ceil_to(value, tick) - floor_to(value, tick) in (0, tick)
