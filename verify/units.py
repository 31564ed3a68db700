"""Exact numbers as people read them: ``37.5``, ``100/3``, ``25 ms``, ``4 Hz``. No floats."""
from __future__ import annotations

from fractions import Fraction

from .syntax import Quantity


def fmt_number(value: Fraction) -> str:
    """An exact rendering: an integer, a terminating decimal, or ``p/q``."""
    value = Fraction(value)
    if value.denominator == 1:
        return str(value.numerator)
    den = value.denominator
    twos = fives = 0
    while den % 2 == 0:
        den //= 2
        twos += 1
    while den % 5 == 0:
        den //= 5
        fives += 1
    if den != 1:
        return f"{value.numerator}/{value.denominator}"
    digits = max(twos, fives)
    scaled = abs(value) * 10**digits
    whole, frac = divmod(int(scaled), 10**digits)
    text = f"{whole}.{str(frac).rjust(digits, '0')}".rstrip("0")
    return ("-" if value < 0 else "") + text


def fmt_quantity(q: Quantity) -> str:
    return f"{fmt_number(q.value)} {q.unit}"


_TIME_SCALES = ((Fraction(1), "s"), (Fraction(1, 1000), "ms"), (Fraction(1, 10**6), "us"), (Fraction(1, 10**9), "ns"))


def fmt_time(seconds: Fraction | None) -> str:
    """A time in the largest unit in which it is at least 1 (``0.5 ms``, ``25 ms``, ``1.2 s``)."""
    if seconds is None:
        return "unbounded"
    seconds = Fraction(seconds)
    if seconds == 0:
        return "0 ms"
    for scale, unit in _TIME_SCALES:
        if abs(seconds) >= scale:
            return f"{fmt_number(seconds / scale)} {unit}"
    return f"{fmt_number(seconds * 10**9)} ns"


def fmt_rate(hertz: Fraction | None) -> str:
    if hertz is None:
        return "unbounded"
    hertz = Fraction(hertz)
    if hertz >= 1000 and (hertz / 1000).denominator == 1:
        return f"{fmt_number(hertz / 1000)} kHz"
    return f"{fmt_number(hertz)} Hz"
