"""Integer time: the one place where exact times (``Fraction`` seconds) become integer ticks and back.

The analyses that count in integers — the CPA fixed point in ``timing/fastrta.py``, the Z3 encoding of
``synth/encode.py``, the job-level evaluator of ``prove/intsim.py`` and the exact search of
``prove/exact.py`` and ``prove/scenario.py`` — choose a ``TimeBase``: a unit of which every time of
their problem is a whole multiple, either the greatest such unit (``TimeBase.gcd_of``: the gcd of the
times, so the integers stay small) or one over a common denominator (``TimeBase.per_second``: any
multiple of the least one works, so it can grow as new times arrive). ``ticks`` is exact: a time that
is not a multiple of the unit is an error, never rounded.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from functools import reduce


def frac_gcd(values: Iterable[Fraction]) -> Fraction | None:
    """The greatest d > 0 with every value an integer multiple of d (None if all are 0)."""
    vals = [Fraction(v) for v in values if v]
    if not vals:
        return None
    den = reduce(math.lcm, (v.denominator for v in vals))
    num = reduce(math.gcd, (abs(v.numerator) * (den // v.denominator) for v in vals))
    return Fraction(num, den)


def frac_lcm(values: Iterable[Fraction]) -> Fraction | None:
    """The least d > 0 that is an integer multiple of every non-zero value (None if all are 0)."""
    vals = [Fraction(v) for v in values if v]
    if not vals:
        return None
    den = reduce(math.lcm, (v.denominator for v in vals))
    num = reduce(math.lcm, (v.numerator * (den // v.denominator) for v in vals))
    return Fraction(num, den)


def ceil_to(value: Fraction, tick: Fraction) -> Fraction:
    """The least multiple of ``tick`` that is at least ``value``."""
    return tick * math.ceil(value / tick)


def floor_to(value: Fraction, tick: Fraction) -> Fraction:
    """The greatest multiple of ``tick`` that is at most ``value``."""
    return tick * math.floor(value / tick)


@dataclass(frozen=True, slots=True)
class TimeBase:
    """Integer time with ``unit`` seconds per tick."""

    unit: Fraction

    def __post_init__(self) -> None:
        if self.unit <= 0:
            raise ValueError(f"a time unit is positive, not {self.unit}")

    @classmethod
    def gcd_of(cls, values: Iterable[Fraction], default: Fraction = Fraction(1)) -> TimeBase:
        """The coarsest base in which every value is whole (``default`` if every value is 0)."""
        return cls(frac_gcd(values) or default)

    @classmethod
    def per_second(cls, denominators: Iterable[int]) -> TimeBase:
        """The base of 1/D seconds, D the least common multiple of ``denominators``."""
        return cls(Fraction(1, math.lcm(*denominators)))

    @property
    def scale(self) -> int:
        """Ticks per second, for a base of 1/D seconds (ValueError for other bases)."""
        if self.unit.numerator != 1:
            raise ValueError(f"{self.unit} s is not one over a whole number")
        return self.unit.denominator

    def ticks(self, value: Fraction) -> int:
        """``value`` in ticks (ValueError if it is not a whole number of them)."""
        if type(value) is not Fraction:
            value = Fraction(value)
        q, r = divmod(value.numerator * self.unit.denominator, value.denominator * self.unit.numerator)
        if r:
            raise ValueError(f"{value} s is not a multiple of the tick {self.unit} s")
        return q

    def seconds(self, ticks: int) -> Fraction:
        """``ticks`` in seconds."""
        return self.unit * ticks

    def whole(self, value: Fraction) -> bool:
        """``value`` is a whole number of ticks."""
        return (value / self.unit).denominator == 1
