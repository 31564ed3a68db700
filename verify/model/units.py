"""Exact numbers as people read them: ``37.5``, ``100/3``, ``25 ms``, ``4 Hz``. No floats."""
from __future__ import annotations

from fractions import Fraction
from math import gcd

from .syntax import FREQUENCY_UNITS, TIME_UNITS, Quantity


def fmt_number(value: Fraction) -> str:
    """An exact rendering: an integer, a terminating decimal, or ``p/q``."""
    if not isinstance(value, (int, Fraction)):
        value = Fraction(value)
    return _fmt_lowest_terms(value.numerator, value.denominator)


def _fmt_ratio(num: int, den: int) -> str:
    """``fmt_number(Fraction(num, den))`` for integers (den > 0), without building the Fraction: reports
    render tens of thousands of numbers."""
    common = gcd(num, den)
    return _fmt_lowest_terms(num // common, den // common)


def _fmt_lowest_terms(num: int, den: int) -> str:
    """``fmt_number`` of num/den in lowest terms (den > 0)."""
    if den == 1:
        return str(num)
    rest = den
    twos = (rest & -rest).bit_length() - 1  # the factors 2 of the denominator
    rest >>= twos
    fives = 0
    while rest % 5 == 0:
        rest //= 5
        fives += 1
    if rest != 1:
        return f"{num}/{den}"
    digits = max(twos, fives)
    whole, frac = divmod(abs(num) * 10**digits // den, 10**digits)  # (exact: den divides 10**digits)
    text = f"{whole}.{str(frac).rjust(digits, '0')}".rstrip("0")
    return ("-" if num < 0 else "") + text


def fmt_quantity(q: Quantity) -> str:
    return f"{fmt_number(q.value)} {q.unit}"


#: the units of ``fmt_time``, largest first, as (10**k, unit): a value of n/d seconds is n·10**k/d units
_TIME_SCALES = ((1, "s"), (1000, "ms"), (10**6, "us"), (10**9, "ns"))


def fmt_time(seconds: Fraction | None) -> str:
    """A time in the largest unit in which it is at least 1 (``0.5 ms``, ``25 ms``, ``1.2 s``)."""
    if seconds is None:
        return "unbounded"
    if not isinstance(seconds, (int, Fraction)):
        seconds = Fraction(seconds)
    num, den = seconds.numerator, seconds.denominator
    if num == 0:
        return "0 ms"
    size = abs(num)
    for factor, unit in _TIME_SCALES:
        if size * factor >= den:  # |seconds| >= 1 unit
            return f"{_fmt_ratio(num * factor, den)} {unit}"
    return f"{_fmt_ratio(num * 10**9, den)} ns"


def fmt_rate(hertz: Fraction | None) -> str:
    if hertz is None:
        return "unbounded"
    hertz = Fraction(hertz)
    if hertz >= 1000 and (hertz / 1000).denominator == 1:
        return f"{fmt_number(hertz / 1000)} kHz"
    return f"{fmt_number(hertz)} Hz"


#: each unit's factor to seconds or hertz as (numerator, denominator)
_UNIT_RATIOS = {unit: factor.as_integer_ratio() for unit, factor in {**TIME_UNITS, **FREQUENCY_UNITS}.items()}


def quantity_base(q: Quantity) -> Fraction:
    """``q.base``: a 10,000-task system reads about 100,000 quantities, and one normalisation of
    integers is a fraction of the cost of ``Fraction`` multiplication (same value)."""
    n, d = q.value.as_integer_ratio()
    a, b = _UNIT_RATIOS[q.unit]
    return Fraction(n * a, d * b)


def quantity_seconds(q: Quantity) -> Fraction:
    """``q.seconds()`` (a frequency read as its period), computed as ``quantity_base``."""
    n, d = q.value.as_integer_ratio()
    a, b = _UNIT_RATIOS[q.unit]
    if q.unit in TIME_UNITS:
        return Fraction(n * a, d * b)
    return Fraction(d * b, n * a) if n else q.seconds()  # (0 Hz: the same error as q.seconds())


def quantity_hertz(q: Quantity) -> Fraction:
    """``q.hertz()`` (a time read as its rate), computed as ``quantity_base``."""
    n, d = q.value.as_integer_ratio()
    a, b = _UNIT_RATIOS[q.unit]
    if q.unit not in TIME_UNITS:
        return Fraction(n * a, d * b)
    return Fraction(d * b, n * a) if n else q.hertz()
