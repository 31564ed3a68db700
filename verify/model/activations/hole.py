"""``activation ?``, ``timer ?`` and ``trigger PORT every ?``: what ``synth`` has to choose (specs/synthesis.md §2)."""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import ClassVar, Literal

from ...core.source import NO_SPAN, Span
from .base import Activation


HoleWhat = Literal["period", "prescaler", "kind"]


@dataclass(frozen=True)
class Hole(Activation):
    """An unknown left for ``synth`` (specs/synthesis.md §2): a timer's period (``timer ?``), a data
    trigger's prescaler (``trigger p every ?``) or the kind of activation (``activation ?``), with the
    range the user allows.

    ``low``, ``high`` and ``step`` bound a period (seconds, each as written: a frequency range gives the
    periods of its ends, in the order written) or a prescaler (integers); None for a bare ``?``.
    ``phase`` is a timer hole's fixed phase, ``port`` a prescaler hole's trigger port. ``text`` is the
    hole as written (canonical: ``timer ? in 25 ms .. 200 ms step 25 ms``), ``range_text`` its range
    (``25 ms .. 200 ms step 25 ms``); ``span`` is the activation, ``range_span`` the ``?`` and its range.

    ``verify.frontend.build.hole_of(node)`` builds it from the syntax node of a hole."""

    kind: ClassVar[str] = "hole"

    what: HoleWhat = "kind"
    low: Fraction | None = None
    high: Fraction | None = None
    step: Fraction | None = None
    phase: Fraction | None = None
    port: str | None = None
    text: str = "activation ?"
    range_text: str = ""
    span: Span = field(default=NO_SPAN, compare=False, repr=False)
    range_span: Span = field(default=NO_SPAN, compare=False, repr=False)

    def describe(self) -> str:
        return "synthesis hole"

    def as_written(self) -> str:
        return self.text

    @property
    def unknown(self) -> bool:
        return True

    @property
    def bounded(self) -> bool:
        """The user gave a range (``? in LOW .. HIGH``)."""
        return self.low is not None
