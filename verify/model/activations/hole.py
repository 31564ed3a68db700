"""``activation ?``, ``timer ?`` and ``trigger PORT every ?``: what ``synth`` has to choose (specs/synthesis.md §2)."""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import ClassVar, Literal, TypedDict

from .. import syntax as s
from ...core.source import NO_SPAN, Span
from .base import Activation


def _seconds(q: s.Quantity | None) -> Fraction | None:
    return q.seconds() if q is not None else None


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

    ``Hole.of(node)`` builds it from the syntax node of a hole."""

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

    @classmethod
    def of(cls, node: s.Activation) -> Hole:
        """The hole that the activation ``node`` (with a ``?``) leaves open."""
        return cls(**_hole_fields(node))

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


class _HoleFields(TypedDict, total=False):
    """The fields of a ``Hole`` read from its syntax node."""

    what: HoleWhat
    low: Fraction
    high: Fraction
    step: Fraction | None
    phase: Fraction | None
    port: str
    text: str
    range_text: str
    span: Span
    range_span: Span


def _hole_fields(node: s.Activation) -> _HoleFields:
    from ...frontend.fmt import format_activation, format_number, format_quantity

    text = format_activation(node)
    if isinstance(node, s.Timer) and isinstance(node.period, s.PeriodHole):
        h = node.period
        bounds: _HoleFields = {}
        range_text = ""
        if h.low is not None and h.high is not None:
            bounds = {"low": h.low.seconds(), "high": h.high.seconds(),
                      "step": h.step.seconds() if h.step is not None else None}
            range_text = f"{format_quantity(h.low)} .. {format_quantity(h.high)}" + (
                f" step {format_quantity(h.step)}" if h.step is not None else "")
        fields: _HoleFields = {"what": "period", "phase": _seconds(node.phase), "text": text,
                               "range_text": range_text, "span": node.span, "range_span": h.span}
        fields.update(bounds)
        return fields
    if isinstance(node, s.Trigger) and isinstance(node.prescaler, s.PrescalerHole):
        ph = node.prescaler
        bounds = {}
        range_text = ""
        if ph.low is not None and ph.high is not None:
            bounds = {"low": Fraction(ph.low.value), "high": Fraction(ph.high.value)}
            range_text = f"{format_number(ph.low.value)} .. {format_number(ph.high.value)}"
        fields = {"what": "prescaler", "port": node.port.text, "text": text, "range_text": range_text,
                  "span": node.span, "range_span": ph.span}
        fields.update(bounds)
        return fields
    return {"what": "kind", "text": text, "span": node.span, "range_span": node.span}
