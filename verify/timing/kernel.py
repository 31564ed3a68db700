"""The kernel the response-time analyses share (specs/timing.md §6, §9): a task's result
(``TaskResponse``), its deadline and best case, demand streams (``Interferer``: ``η⁺(Δ)·C``, with the
causal caps of §6.2 and the suspension jitter of a cooperative task, §6.3), the activation causes of a
data-triggered task, and the least fixed point of a busy window under a step budget.

The reference analysis per core (``rta``), the fast one (``fastrta``) and the executor analyses
(``executors``, ``multithreaded``) build on it; it imports none of them.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from collections.abc import Sequence

from ..model.system import LinkModel, SystemModel, TaskModel
from .rates import EventModel

ZERO = Fraction(0)
MAX_JOBS = 1000  # jobs per busy window before giving up
MAX_STEPS = 100_000  # fixed-point steps per task


@dataclass(frozen=True)
class TaskResponse:
    """Response-time bounds of one task, measured from its release (§6).

    ``wcrt`` is the bound every later step uses: the user's ``wcrt`` bound if given (rule "user
    bound"), else ``wcrt_computed``; None when no bound was found (``failure``
    says why). ``blocking`` is the per-job cooperative blocking ``βᵢ``; ``busy_jobs`` the number of
    jobs Q in the longest busy window; ``critical_job`` the q that gave the maximum.
    """

    task: str
    core: str
    priority: int
    bcrt: Fraction
    wcrt: Fraction | None
    wcrt_computed: Fraction | None
    rule: str
    deadline: Fraction | None
    deadline_rule: str
    blocking: Fraction | None
    hold: Fraction | None  # Eᵢ: start to completion, what a sibling waits for
    busy_jobs: int | None
    critical_job: int | None
    #: hp(i) in declaration order, then the remote siblings (a view of the core's tasks: ``interferers``)
    interferers: Sequence[str]
    failure: str | None = None

    @property
    def schedulable(self) -> bool:
        return self.wcrt is not None and (self.deadline is None or self.wcrt <= self.deadline)


def deadline_of(task: TaskModel, events: EventModel) -> tuple[Fraction | None, str]:
    """The deadline of ``task`` and where it comes from: given, else ``A⁺`` (§6.4); an arrival task (§6.6)
    has none."""
    if task.arrival:
        return None, "none (the work of taking arrivals)"
    if task.deadline is not None:
        return task.deadline, "given"
    if events.a_max is not None:
        return events.a_max, "A⁺ (max inter-activation)"
    return None, "none (A⁺ not bounded)"


def bcrt(task: TaskModel) -> Fraction:
    """The best-case response time: ``bcet`` — a job completes no earlier than its release plus its
    execution time, which is at least ``bcet`` (§6.4)."""
    return task.bcet


def ratio(value: Fraction) -> str:
    """An exact fraction as ``p/q`` (or an integer)."""
    return str(value.numerator) if value.denominator == 1 else f"{value.numerator}/{value.denominator}"


# ================================================================== demand streams


@dataclass(frozen=True)
class Interferer:
    """A stream of demand: ``η⁺(Δ) · cost`` with ``η⁺(Δ) = ⌈(Δ + jitter)/period⌉``, capped for the
    q-th job's window by ``causal_cap(q)`` when every activation of the stream descends from the
    analysed task's own completions (§6.2)."""

    task: str
    cost: Fraction | None
    period: Fraction | None
    jitter: Fraction | None
    silent: bool = False
    prescalers: tuple[int, ...] | None = None  # causal path back to the analysed task, nearest last
    carry: int | None = None
    extras: tuple[int, ...] = ()  # per hop of the path: events without a new arrival (AND: 1)
    local: tuple[int, tuple[int, ...]] | None = None  # a local path's (carry for L⁺ = 0, extras)
    before: Fraction | None = None  # a job of it was released at most this long before the window (pipeline)

    def demand(self, window: Fraction, q: int = 1) -> Fraction | None:
        if self.silent or window <= 0:
            return ZERO
        cap = self.causal_cap(q)
        if self.cost is None or self.period is None or self.jitter is None:
            # a capped stream (``causally_capped``) costs the task's wcet: its cost is known
            return None if cap is None or self.cost is None else cap * self.cost
        count = -((-(window + self.jitter)) // self.period)
        if self.before is not None:  # that job is not in the window (verify.timing.pipeline)
            count = min(count, -((-(window + self.before + self.jitter)) // self.period) - 1)
        return (count if cap is None else min(count, cap)) * self.cost

    def causal_cap(self, q: int) -> int | None:
        """At most ``q − 1 + carry`` completions of the analysed task can cause releases in its
        q-job busy window; at each hop an AND compound adds the one event a value waiting since
        before the window may complete, and the prescaler divides (rounded up)."""
        if self.prescalers is None or self.carry is None:
            return None
        cap = self._nested(q - 1 + self.carry, self.extras or (0,) * len(self.prescalers))
        if self.local is not None:
            cap = min(cap, self._nested(q - 1 + self.local[0], self.local[1]))
        return cap

    def _nested(self, n: int, extras: tuple[int, ...]) -> int:
        for k, extra in zip(reversed(self.prescalers or ()), reversed(extras)):
            n = -((-(n + extra)) // k)
        return n

    def rate(self) -> Fraction | None:
        if self.silent:
            return ZERO
        if self.cost is None or self.period is None:
            return None
        return self.cost / self.period


def interferer(system: SystemModel, task: TaskModel, events: EventModel, response: Fraction | None,
               cost: Fraction | None) -> Interferer:
    jitter = events.jitter_min
    if jitter is not None:
        extra = suspension_jitter(system, task, response)
        jitter = None if extra is None else jitter + extra
    return Interferer(task.id, cost, events.period_min, jitter, events.silent)


def suspension_jitter(system: SystemModel, task: TaskModel, response: Fraction | None) -> Fraction | None:
    """A cooperative task with siblings may wait for the token: extra jitter ``R − C`` (§6.3)."""
    if not siblings(system, task):
        return ZERO
    if response is None:
        return None
    return max(ZERO, response - task.wcet)


def siblings(system: SystemModel, task: TaskModel) -> tuple[TaskModel, ...]:
    """The other cooperative tasks of ``task``'s instance (empty unless ``task`` is cooperative)."""
    if task.kind != "cooperative":
        return ()
    return tuple(t for t in system.tasks if t.instance == task.instance and t.kind == "cooperative"
                 and t.id != task.id)


def causes(system: SystemModel, task: TaskModel) -> list[tuple[int, int, LinkModel]]:
    """The connections whose arrivals cause ``task``'s releases, each with (prescaler, events without
    a new arrival on it, connection): the one of a single-port trigger (0), or one per connected member
    of an AND compound (1: a fresh value may be waiting when the window opens). None for a timer, a
    sporadic source or an OR compound (any member alone may cause an event)."""
    act = task.activation
    if act.single_port is not None:
        link = system.link_into(f"{task.instance}.{act.single_port}")
        return [] if link is None else [(act.release_every, 0, link)]
    if act.all_members:
        links = [system.link_into(f"{task.instance}.{m}") for m in act.trigger_members]
        return [(act.release_every, 1, link) for link in links if link is not None]
    return []


# ================================================================== the fixed point


class Budget:
    """The fixed-point steps left for one task (all its busy-window jobs together)."""

    def __init__(self, steps: int = MAX_STEPS):
        self.left = steps

    def take(self) -> bool:
        self.left -= 1
        return self.left >= 0


def least_fixed_point(base: Fraction, start: Fraction, streams: list[Interferer], q: int = 1,
                      budget: Budget | None = None) -> tuple[Fraction | None, str | None]:
    """The least w ≥ start with ``w = base + Σ demand(w)`` (iterated from ``start``, which must not
    exceed it), or None with a reason: the demand is unbounded, the streams' utilisation is at least 1
    (no fixed point), or the step budget runs out."""
    load = load_of([s for s in streams if s.prescalers is None or s.carry is None])
    if load is None:
        return None, "the interference is not bounded"
    if load is not None and load >= 1 and base > 0:
        # w ↦ base + Σ⌈(w + J)/P⌉·C ≥ base + U·w > w: no fixed point exists
        return None, f"the interfering utilisation is {ratio(load)} (at least 1)"
    w, budget = start, budget or Budget()
    while budget.take():
        new = base
        for s in streams:
            demand = s.demand(w, q)
            if demand is None:
                return None, f"the activations of `{s.task}` are not bounded"
            new += demand
        if new == w:
            return w, None
        w = new
    return None, f"no fixed point within {MAX_STEPS} iteration steps"


def load_of(streams: list[Interferer]) -> Fraction | None:
    """The utilisation ``Σ C/P`` of ``streams`` (a silent one 0), or None when one is not bounded."""
    total = ZERO
    for s in streams:
        rate = s.rate()
        if rate is None:
            return None
        total += rate
    return total
