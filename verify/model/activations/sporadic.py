"""``sporadic MIN .. MAX``: releases at least MIN and at most MAX apart (specs/timing.md §3)."""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import ClassVar

from ...core.source import NO_SPAN, Span
from ..units import fmt_time
from .base import Activation


@dataclass(frozen=True)
class SporadicSource(Activation):
    """Activations at least ``min_interarrival`` and at most ``max_interarrival`` apart; the first one
    anywhere in ``[0, max_interarrival)``."""

    kind: ClassVar[str] = "sporadic"

    min_interarrival: Fraction
    max_interarrival: Fraction
    span: Span = field(default=NO_SPAN, compare=False, repr=False)

    @property
    def gaps(self) -> tuple[Fraction, Fraction]:
        return (self.min_interarrival, self.max_interarrival)

    def describe(self) -> str:
        return f"sporadic {fmt_time(self.min_interarrival)} .. {fmt_time(self.max_interarrival)}"
