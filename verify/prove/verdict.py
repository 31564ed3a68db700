"""Result objects of ``prove`` (specs/proof.md §7).

One ``Verdict`` per checked property: every chain spec (reaction time, data age, jitter) and the
deadline of every task. ``status`` is "proved", "violated" or "undecided"; ``method`` says what
established it: "bound" (the compositional analysis of specs/timing.md), "refined-bound" (the same
with exact response times, specs/proof.md §4.8), "exact-enumeration" or
"exact-z3" (the exact search of specs/proof.md §4–§5), or "search" (a falsifying search, which can
only establish violations).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

from ..core.diagnostics import Diagnostic
from ..core.source import NO_SPAN, Span
from ..timing.chains import SPEC_WORDS
from .scenario import ConcreteScenario, Measured, Target

METHODS = ("bound", "refined-bound", "exact-enumeration", "exact-z3", "search")
STATUSES = ("proved", "violated", "undecided")

EXIT_OK, EXIT_VIOLATED, EXIT_UNDECIDED = 0, 1, 3

#: the latency (``verify.prove.sim`` kind) behind each spec kind, by data-age variant
def sim_kind(spec_kind: str, variant: str) -> str:
    if spec_kind == "reaction_time":
        return "reaction_time"
    if spec_kind == "deadline":
        return "response"
    return "data_age" if variant == "reduced" else "data_age_nonreduced"


@dataclass(frozen=True)
class Counterexample:
    """A concrete run breaking a spec: ``scenario`` replays (``verify.prove.sim.simulate``) to a trace in
    which ``sample`` (a ``verify.prove.sim.Sample`` or a response sample) has ``latency``. For a jitter
    spec, ``best_scenario``/``best_sample`` is a second run with a small data age, and ``latency``
    is the difference of the two."""

    target: Target
    scenario: ConcreteScenario
    sample: object
    latency: Fraction
    best_scenario: ConcreteScenario | None = None
    best_sample: object | None = None

    @staticmethod
    def of(target: Target, worst: Measured, best: Measured | None = None) -> Counterexample:
        w = worst.values[target].worst
        assert w is not None, "a counterexample is made of a scenario that measured the target"
        if best is None:
            return Counterexample(target, worst.scenario, w, w.value)
        b = best.values[target].best
        assert b is not None, "a counterexample is made of a scenario that measured the target"
        return Counterexample(target, worst.scenario, w, w.value - b.value, best.scenario, b)


@dataclass(frozen=True)
class Verdict:
    """The outcome for one property.

    ``subject`` "chain" (``name`` the chain) or "task" (``name`` the task id); ``kind``
    "reaction_time", "data_age", "jitter" or "deadline"; ``spec`` the bound asked for; ``bound``
    the analysis' bound (None: unbounded); ``exact`` the exact worst case (supremum over all runs)
    when an exact method established it; ``refined`` the bound recomputed with exact response times
    that proved it (method "refined-bound"); ``margin`` = spec − exact when known, else spec − refined
    when known, else spec − bound.
    """

    subject: str
    name: str
    kind: str
    spec: Fraction
    status: str
    method: str
    bound: Fraction | None
    exact: Fraction | None = None
    exact_best: Fraction | None = None  # jitter: the exact best case of the data age
    refined: Fraction | None = None  # the bound recomputed with exact response times (§4.8)
    counterexample: Counterexample | None = None
    variant: str = ""
    note: str = ""
    explored: int = 0
    span: Span = field(default=NO_SPAN, compare=False)
    related: tuple[tuple[Span, str], ...] = field(default=(), compare=False)

    @property
    def margin(self) -> Fraction | None:
        value = self.exact if self.exact is not None else self.refined if self.refined is not None else self.bound
        if self.status == "violated" and self.counterexample is not None and self.exact is None:
            value = self.counterexample.latency
        return None if value is None else self.spec - value

    @property
    def label(self) -> str:
        what = SPEC_WORDS[self.kind]
        return f"chain {self.name}: {what}" if self.subject == "chain" else f"task {self.name}: {what}"


@dataclass(frozen=True)
class ProofResult:
    """All verdicts of one system, the diagnostics for the ones not proved, and how much was searched."""

    system: str
    verdicts: tuple[Verdict, ...]
    diagnostics: tuple[Diagnostic, ...]
    data_age_variant: str = "reduced"
    explored: int = 0
    budget: int = 0

    @property
    def violated(self) -> tuple[Verdict, ...]:
        return tuple(v for v in self.verdicts if v.status == "violated")

    @property
    def undecided(self) -> tuple[Verdict, ...]:
        return tuple(v for v in self.verdicts if v.status == "undecided")

    @property
    def exit_code(self) -> int:
        if self.violated:
            return EXIT_VIOLATED
        if self.undecided or any(d.code == "E312" for d in self.diagnostics):  # (a task nothing proves bounded)
            return EXIT_UNDECIDED
        return EXIT_OK

    def verdict(self, name: str, kind: str) -> Verdict:
        return next(v for v in self.verdicts if v.name == name and v.kind == kind)
