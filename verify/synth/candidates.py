"""Every decision of a synthesis problem as an ordered, finite list of candidate activations.

A *choice* is a task whose activation synthesis decides: every hole, and — when statements are
tracked for an unsat core — every task whose rate a relaxable statement fixes (specs/synthesis.md §2).

* ``timer ? in LOW .. HIGH step S``: the grid LOW, LOW + S, … up to HIGH.
* ``timer ? in LOW .. HIGH`` (no step): LOW, HIGH, the default grid inside the range, and the
  fastest and slowest period the activation constraint allows if they lie inside.
* ``timer ?``: the default grid plus the fastest and slowest period the constraint allows.
* ``every ? in A .. B``: A … B; ``every ?``: the default prescalers ``DEFAULT_PRESCALERS``.
* ``activation ?``: the timer candidates of ``timer ?`` and, for every in-port or compound in-port the
  task may trigger on (it reads every member; the members are connected), the default prescalers.

The default prescalers are the usual divisors 1 … 100 with few prime factors (their least common
multiple is 1,200, where that of all of 1 … 100 has 41 digits: exact rates stay small integers in
the encoding even through chains of triggers); ``every ? in 1 .. 100`` asks for every value.

Each candidate records the statements that forbid it (``excluded``): a range, a fixed rate, an end of
the activation constraint. A relaxed timer may take the default grid, a relaxed prescaler
the default prescalers. Untracked problems drop those candidates; tracked ones keep them and let
the statement's literal forbid them. Candidates are ordered canonically (timers by period, then
triggers by port name and prescaler), never by declaration order. Default grid: the usual robotics
and automotive periods (WATERS 2015 and ROS drivers), ``DEFAULT_PERIODS``.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Literal

from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..model.activations import DataTriggered, Hole, Periodic
from ..model.system import SystemModel, TaskModel
from ..frontend.resolve import SystemScope
from .statements import Statement, statement_index

MS = Fraction(1, 1000)
DEFAULT_PERIODS: tuple[Fraction, ...] = tuple(ms * MS for ms in (1, 2, 5, 10, 20, 25, 40, 50, 100, 200, 250, 500, 1000))
#: the prescalers of `every ?` and `activation ?`, and what a relaxed prescaler (an explicit `every K`,
#: or a prescaler range) may take besides its own values
DEFAULT_PRESCALERS: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 50, 100)
MAX_CANDIDATES = 4096  # per choice; a finer grid is refused (E403)

#: how a data trigger's members make an activation event (``DataTriggered.mode``)
TriggerMode = Literal["single", "and", "or"]


@dataclass(frozen=True)
class Candidate:
    """One way to activate a task: a timer (``Periodic``, with the binding's phase) or a data trigger
    (``DataTriggered``: port, members, mode, prescaler). Everything else is asked of the activation."""

    activation: Periodic | DataTriggered

    @property
    def group(self) -> str:
        """Candidates of one group differ only in speed (period or prescaler)."""
        port = self.activation.trigger_port
        return self.activation.kind if port is None else f"{self.activation.kind} {port}"

    @property
    def speed(self) -> Fraction:
        """Smaller is faster: the period of a timer, the prescaler of a trigger."""
        period = self.activation.strict_period
        return period if period is not None else Fraction(self.activation.release_every)

    def sort_key(self) -> tuple[bool, str, Fraction]:
        return (self.activation.strict_period is None, self.activation.trigger_port or "", self.speed)

    @property
    def rate(self) -> Fraction | None:
        """The activation rate of a timer candidate (a trigger's depends on its writers)."""
        period = self.activation.strict_period
        return 1 / period if period is not None else None

    def text(self) -> str:
        return self.activation.as_written()


@dataclass(frozen=True)
class Choice:
    """A task's decision: its candidates in canonical order, and per candidate the keys of the
    statements that forbid it."""

    task: str
    candidates: tuple[Candidate, ...]
    excluded: tuple[tuple[str, ...], ...]
    hole: Hole | None = None  # the hole; None for a relaxable fixed binding
    slowest: int = field(default=0, compare=False)

    @functools.cached_property
    def activations(self) -> tuple[Periodic | DataTriggered, ...]:
        """The activation of every candidate, in order."""
        return tuple(c.activation for c in self.candidates)

    def allowed(self, off: frozenset[str] = frozenset()) -> tuple[int, ...]:
        """Indices of the candidates no statement (other than those in ``off``) forbids."""
        return tuple(i for i, ex in enumerate(self.excluded) if all(k in off for k in ex))


class TooManyCandidates(ValueError):
    """A hole whose range and grid give more than ``MAX_CANDIDATES`` values."""

    def __init__(self, task: TaskModel, count: int):
        super().__init__(f"{task.id}: {count} candidates")
        self.task, self.count = task, count

    def diagnostic(self) -> Diagnostic:
        """E403 at the hole."""
        return DiagnosticSink().emit(
            "E403", f"`{self.task.id}` would have {self.count} candidate values; synth considers at most "
            f"{MAX_CANDIDATES} per hole", self.task.activation.span, "too many candidates",
            help="use a coarser `step`, or a narrower range")


# ================================================================== trigger ports


def trigger_ports(model: SystemModel, task: TaskModel,
                  scope: SystemScope | None) -> dict[str, tuple[TriggerMode, tuple[str, ...]]]:
    """The ports ``task`` may be data-triggered on, by name: (mode, members). Validation's rules: the
    task reads every member, the members are connected (for OR, at least one)."""
    ports: dict[str, tuple[TriggerMode, tuple[str, ...]]] = {}
    comp = scope.component_of.get(task.instance) if scope is not None else None
    if comp is not None:
        for p in comp.component.in_ports:
            ports[p.name.text] = ("single", (p.name.text,))
        for c in comp.component.compounds:
            ports[c.name.text] = (c.mode, tuple(m.text for m in c.members))
    else:
        for r in task.reads:
            ports[r.port] = ("single", (r.port,))

    def usable(mode: str, members: tuple[str, ...]) -> bool:
        if not all(task.reads_port(m) for m in members):
            return False
        linked = [model.link_into(f"{task.instance}.{m}") is not None for m in members]
        return any(linked) if mode == "or" else all(linked)

    return {name: ports[name] for name in sorted(ports) if usable(*ports[name])}


# ================================================================== domains


def _constraint_periods(task: TaskModel) -> list[Fraction]:
    """The fastest and slowest period the activation constraint allows."""
    return [1 / r for r in (task.max_rate, task.min_rate) if r is not None and r > 0]


def _grid(lo: Fraction, hi: Fraction, step: Fraction, task: TaskModel) -> list[Fraction]:
    count = (hi - lo) // step + 1
    if count > MAX_CANDIDATES:
        raise TooManyCandidates(task, int(count))
    return [lo + i * step for i in range(int(count))]


def period_values(h: Hole, task: TaskModel) -> tuple[list[Fraction] | None, list[Fraction]]:
    """(the hole's own range values or None for a bare ``?``, its default candidates)."""
    extremes = _constraint_periods(task)
    if h.low is None or h.high is None:
        return None, sorted(set(DEFAULT_PERIODS) | set(extremes))
    lo, hi = sorted((h.low, h.high))
    if h.step is not None:
        values = _grid(h.low, h.high, h.step, task)
    else:
        inside = [p for p in list(DEFAULT_PERIODS) + extremes if lo <= p <= hi]
        values = sorted({lo, hi, *inside})
    return values, values


def prescaler_values(h: Hole, task: TaskModel) -> tuple[list[int] | None, list[int]]:
    if h.low is None or h.high is None:
        return None, list(DEFAULT_PRESCALERS)
    lo, hi = int(h.low), int(h.high)
    if hi - lo + 1 > MAX_CANDIDATES:
        raise TooManyCandidates(task, hi - lo + 1)
    return list(range(lo, hi + 1)), list(range(lo, hi + 1))


class _Builder:
    """Collects candidates with the statement keys that exclude each."""

    def __init__(self, task: TaskModel, slots: dict[str, str]):
        self.task, self.slots = task, slots
        self.items: dict[Candidate, set[str]] = {}

    def add(self, act: Periodic | DataTriggered, *excluders: str | None) -> None:
        period, phase = act.strict_period, act.fixed_phase
        if period is not None and phase is not None and period <= phase:
            return  # a phase lies in [0, period)
        keys = self.items.setdefault(Candidate(act), set())
        keys.update(k for k in excluders if k)
        if period is not None:
            keys.update(self._constraint_excluders(1 / period))

    def _constraint_excluders(self, rate: Fraction) -> list[str]:
        t, out = self.task, []
        if t.min_rate is not None and rate < t.min_rate:
            out.append(self.slots.get("min_rate") or self.slots.get("rate"))
        if t.max_rate is not None and rate > t.max_rate:
            out.append(self.slots.get("max_rate") or self.slots.get("rate"))
        return [k for k in out if k]

    def choice(self, hole: Hole | None, drop_excluded: bool) -> Choice:
        if len(self.items) > MAX_CANDIDATES:
            raise TooManyCandidates(self.task, len(self.items))
        cands = sorted(self.items, key=Candidate.sort_key)
        if drop_excluded:
            cands = [c for c in cands if not self.items[c]]
        excluded = tuple(tuple(sorted(self.items[c])) for c in cands)
        return make_choice(self.task.id, tuple(cands), excluded, hole)


def make_choice(task: str, cands: tuple[Candidate, ...], excluded: tuple[tuple[str, ...], ...],
                hole: Hole | None) -> Choice:
    """A choice; ``slowest`` is the slowest allowed timer candidate (else the slowest allowed one)."""
    allowed = [i for i, ex in enumerate(excluded) if not ex] or list(range(len(cands)))
    slowest = max(allowed, key=lambda i: (cands[i].activation.strict_period is not None, cands[i].speed), default=0)
    return Choice(task, cands, excluded, hole, slowest)


def task_choice(model: SystemModel, task: TaskModel, scope: SystemScope | None, statements: tuple[Statement, ...],
                tracked: bool) -> Choice | None:
    """The choice of ``task``, or None when its activation is not decided by synthesis. Untracked:
    only holes, with every excluded candidate dropped. Tracked: also relaxable fixed bindings, with
    the default grid (or prescalers) added so that relaxing a statement widens the choice."""
    slots = statement_index(statements).get(task.id, {})
    b = _Builder(task, slots)
    act = task.activation
    if isinstance(act, Hole):
        _hole_candidates(b, model, task, act, scope, slots, tracked)
        hole: Hole | None = act
    elif tracked and isinstance(act, Periodic) and "rate" in slots:
        bound = Periodic(act.period, act.phase)
        b.add(bound)
        for p in _timer_defaults(task):  # a relaxed binding leaves the phase unknown too
            cand = Periodic(p)
            b.add(cand, slots["rate"] if cand != bound else None)
        hole = None
    elif tracked and isinstance(act, DataTriggered) and "rate" in slots:
        for k in sorted({act.prescaler, *DEFAULT_PRESCALERS}):
            b.add(DataTriggered(act.port, act.members, act.mode, k), slots["rate"] if k != act.prescaler else None)
        hole = None
    else:
        return None
    return b.choice(hole, drop_excluded=not tracked)


def _timer_defaults(task: TaskModel) -> list[Fraction]:
    return sorted(set(DEFAULT_PERIODS) | set(_constraint_periods(task)))


def _hole_candidates(b: _Builder, model: SystemModel, task: TaskModel, hole: Hole,
                     scope: SystemScope | None, slots: dict[str, str], tracked: bool) -> None:
    rng = slots.get("range")
    if hole.what == "period":
        own, values = period_values(hole, task)
        for p in values:
            b.add(Periodic(p, hole.phase))
        if tracked and own is not None:
            for p in _timer_defaults(task):
                b.add(Periodic(p, hole.phase), rng if p not in own else None)
    elif hole.what == "prescaler" and hole.port is not None:
        mode, members = trigger_ports(model, task, scope).get(hole.port, ("single", (hole.port,)))
        own_k, ks = prescaler_values(hole, task)
        extra = DEFAULT_PRESCALERS if tracked and own_k is not None else ()
        for k in sorted(set(ks) | set(extra)):
            b.add(DataTriggered(hole.port, members, mode, k), rng if own_k is not None and k not in own_k else None)
    else:  # activation ?
        for p in _timer_defaults(task):
            b.add(Periodic(p))
        for port, (mode, members) in trigger_ports(model, task, scope).items():
            for k in DEFAULT_PRESCALERS:
                b.add(DataTriggered(port, members, mode, k))


def build_choices(model: SystemModel, scope: SystemScope | None, statements: tuple[Statement, ...],
                  tracked: bool) -> dict[str, Choice]:
    """Every choice of ``model``, keyed by task id in sorted (canonical) order."""
    out: dict[str, Choice] = {}
    for task in sorted(model.tasks, key=lambda t: t.id):
        choice = task_choice(model, task, scope, statements, tracked)
        if choice is not None:
            out[task.id] = choice
    return out


def describe_hole(choice: Choice) -> str:
    """What the user wrote for a hole, e.g. ``timer ? in 25 ms .. 200 ms step 25 ms``."""
    return choice.hole.text if choice.hole is not None else "(fixed binding)"

