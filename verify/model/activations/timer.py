"""``timer PERIOD [phase PHASE]``: a periodic timer (specs/timing.md §3)."""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import ClassVar

from ...core.source import NO_SPAN, Span
from ..units import fmt_time
from .base import Activation


@dataclass(frozen=True)
class Periodic(Activation):
    """A periodic timer. ``phase`` None means unknown (any offset in [0, period))."""

    kind: ClassVar[str] = "timer"
    offset_name: ClassVar[str] = "phase"

    period: Fraction
    phase: Fraction | None = None
    #: the activation in the binding (NO_SPAN when synthesised)
    span: Span = field(default=NO_SPAN, compare=False, repr=False)

    @property
    def gaps(self) -> tuple[Fraction, Fraction]:
        return (self.period, self.period)

    @property
    def fixed_phase(self) -> Fraction | None:
        return self.phase

    @property
    def strict_period(self) -> Fraction:
        return self.period

    def describe(self) -> str:
        return f"timer {fmt_time(self.period)}"

    def as_written(self) -> str:
        phase = f" phase {fmt_time(self.phase)}" if self.phase is not None else ""
        return f"timer {fmt_time(self.period)}{phase}"
