"""End-to-end latency bounds of cause-effect chains (specs/timing.md §7).

Every bound is a sum of per-step terms, each produced by one named rule:

* "first-task sampling" (reaction time): ``W⁺₁ + R₁`` — a stimulus waits at most W⁺₁ for the next
  activation of τ₁, whose job completes within R₁ (Davare et al. 2007).
* per hop p → i, by how i takes the hop's value:
  - "register sampling (Davare)": reaction ``d⁺ + W⁺ᵢ + Rᵢ``, data age ``d⁺ + A⁺ₚ + Rₚ``;
  - "data trigger k=1" / "data trigger prescaler k": reaction ``d⁺ + δ⁺ₚ(k) + Rᵢ`` with
    ``δ⁺ₚ(k)`` the span of k consecutive outputs of p (0 for k = 1), data age ``d⁺ + Rₚ``;
  - "AND join": reaction ``d⁺ + (wait for the other members) + δ⁺_AND(k) + Rᵢ``, data age as
    a register; an OR member is triggered for the reaction and a register for the data age;
  - "same-core priority (Dürr et al. CASES 2019)": when p and i share a core, p's priority is
    strictly higher, the delay is exactly 0 and p cannot wait for a cooperative token while i
    starts (§7.6, equations (7.6a) and (7.6b)): data age ``A⁺ₚ``, reaction ``W⁺ᵢ + Rᵢ − Rₚ``,
    used whenever smaller than the rule above;
* "last-task response" (data age): ``Rₙ``;
* "non-reduced origin" (non-reduced data age only, on τ₁'s step): ``A⁺₁``.

Where it is smaller, the data age is the least sum over three ages per task — of a job at its
release, at its read (start) and at its completion (§7.7): the register and same-core terms bound
the reader's age at its read, from which its job completes within the start-to-completion time
``Eᵢ`` ("read-time age (start to completion)": ``d⁺ + Eₚ`` for a trigger, ``Eₙ`` at the end); an AND
member's value waits at most the other members' ``W⁺`` ("AND join age": ``d⁺ + Rₚ + maxₘ W⁺ₘ``); and a
writer with a higher-priority reader it triggers on its core, without delay, is one busy interval
from the writer's read to the reader's completion ("same-core trigger pair": ``Jₚᵢ``).

Reaction time is non-reduced (from the stimulus), data age reduced by default (from τ₁'s read,
Günzel et al. 2024); the other variants follow by adding or removing τ₁'s sampling term. Best cases
are ``Σ bcetᵢ + Σ d⁻`` (rule "best case", one term per step). ``None`` means unbounded. Dürr et
al. 2019 and Becker et al. 2017 give the job-chain view these terms are derived from.

This module holds the results, the context the rules read and the per-step rules; ``endtoend`` sums
the steps into a chain's bounds (``chain_bounds``) and takes the least path over the read-time ages.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property
from collections.abc import Iterable, Mapping

from ..core.construct import direct_constructor
from ..model.activations import Activation, DataTriggered, Periodic, SporadicSource
from ..model.system import HopModel, LinkModel, SystemModel, TaskModel
from ..model.units import fmt_time
from .rates import ActivationInfo, EventModel, arrival_model, combine_and, exact_sum
from .kernel import TaskResponse, interferer, least_fixed_point
from .rta import cooperative_counts

ZERO = Fraction(0)

REGISTER = "register sampling (Davare)"
FIRST = "first-task sampling"
LAST = "last-task response"
AND_JOIN = "AND join"
SAME_CORE = "same-core priority (Dürr et al. CASES 2019)"
ORIGIN = "non-reduced origin"
BEST = "best case"
ORIGIN_BEST = "least read gap of τ₁"
READ_AGE = "read-time age (start to completion)"
AND_AGE = "AND join age"
PAIR = "same-core trigger pair"


def trigger_rule(k: int) -> str:
    return "data trigger k=1" if k == 1 else f"data trigger prescaler k={k}"


# ================================================================== results


@dataclass(frozen=True)
class Term:
    """One contribution: ``value = Σ parts`` (None if a part is unbounded), produced by ``rule``."""

    rule: str
    value: Fraction | None
    parts: tuple[tuple[str, Fraction | None], ...]
    note: str = ""


@dataclass(frozen=True)
class Step:
    """One line of a chain's breakdown: τ₁'s sampling, a hop, or τₙ's response.

    ``reaction``/``data_age`` are the step's worst-case contributions (None: the step adds nothing
    to that bound); ``best`` its best-case contribution (``bcet`` of the task reached, plus ``d⁻``)
    and ``best_term`` the same with its rule and parts. ``data_age_non_reduced`` and
    ``best_non_reduced`` are what the non-reduced data age adds on this step beyond ``data_age`` and
    ``best`` (only τ₁'s step has them: ``A⁺₁`` and the least read gap of τ₁, §7.5).
    """

    kind: str  # "first" | "hop" | "last"
    label: str
    writer: str | None
    reader: str
    source: str | None
    target: str | None
    reaction: Term | None
    data_age: Term | None
    best: Fraction
    best_term: Term
    data_age_non_reduced: Term | None
    best_non_reduced: Term | None


@dataclass(frozen=True)
class Bound:
    """A latency's worst and best case; ``jitter`` = worst − best."""

    worst: Fraction | None
    best: Fraction
    rule: str

    @property
    def jitter(self) -> Fraction | None:
        return None if self.worst is None else self.worst - self.best


#: how a spec's (or a deadline's) kind is named in messages and reports
SPEC_WORDS = {"reaction_time": "reaction time", "data_age": "data age", "jitter": "jitter", "deadline": "deadline"}


@dataclass(frozen=True)
class SpecCheck:
    """A chain spec against its bound: ``margin = spec − bound`` (None: unbounded). The bound is an upper
    bound, so a spec at or above it is proved; below it, the bound proves nothing either way (``status``
    "undecided": ``prove`` decides it)."""

    kind: str  # "reaction_time" | "data_age" | "jitter"
    spec: Fraction
    bound: Fraction | None
    variant: str

    @property
    def margin(self) -> Fraction | None:
        return None if self.bound is None else self.spec - self.bound

    @property
    def ok(self) -> bool:
        return self.bound is not None and self.bound <= self.spec

    @property
    def status(self) -> str:
        """"proved" (by the bound) or "undecided" (not proved by it), in the words of ``prove``."""
        return "proved" if self.ok else "undecided"


@dataclass(frozen=True)
class ChainBounds:
    """All bounds of one chain. ``data_age`` and ``jitter`` follow ``data_age_variant``.

    ``dominating_*`` are step indices: the step with the largest term of that bound (§7.5); for the
    non-reduced data age, τ₁'s step counts with its ``data_age_non_reduced`` term."""

    name: str
    tasks: tuple[str, ...]
    steps: tuple[Step, ...]
    reaction_time: Bound
    reaction_time_reduced: Bound
    data_age_reduced: Bound
    data_age_non_reduced: Bound
    data_age_variant: str
    specs: tuple[SpecCheck, ...]
    dominating_reaction: int | None
    dominating_data_age: int | None
    dominating_data_age_non_reduced: int | None
    problem: str | None = None

    def bound(self, kind: str) -> Bound:
        """The bound of a latency kind as ``verify.prove.sim.KINDS`` names it: "reaction_time",
        "reaction_time_reduced", "data_age" (reduced) or "data_age_nonreduced"."""
        return {"reaction_time": self.reaction_time, "reaction_time_reduced": self.reaction_time_reduced,
                "data_age": self.data_age_reduced, "data_age_reduced": self.data_age_reduced,
                "data_age_nonreduced": self.data_age_non_reduced,
                "data_age_non_reduced": self.data_age_non_reduced}[kind]

    @property
    def data_age(self) -> Bound:
        return self.data_age_reduced if self.data_age_variant == "reduced" else self.data_age_non_reduced

    @property
    def dominating_age(self) -> int | None:
        """The step dominating the data age of ``data_age_variant``."""
        return self.dominating_data_age if self.data_age_variant == "reduced" else self.dominating_data_age_non_reduced

    @property
    def jitter(self) -> Fraction | None:
        return self.data_age.jitter

    @property
    def reaction_jitter(self) -> Fraction | None:
        return self.reaction_time.jitter


#: the constructors of the objects above, built by the thousand (``verify.core.construct``)
_new_term = direct_constructor(Term)
_new_step = direct_constructor(Step)


# ================================================================== context


@dataclass(frozen=True)
class Timing:
    """What the chain rules read: rates, event models and response times of every task."""

    system: SystemModel
    infos: Mapping[str, ActivationInfo]
    events: Mapping[str, EventModel]
    responses: Mapping[str, TaskResponse]

    def R(self, task: str) -> Fraction | None:  # noqa: N802 - the paper's name
        return self.responses[task].wcrt

    def B(self, task: str) -> Fraction:  # noqa: N802
        return self.responses[task].bcrt

    def bcet(self, task: str) -> Fraction:
        return self.system.task(task).bcet

    @cached_property
    def cooperative_count(self) -> Mapping[str, int]:
        """The number of cooperative tasks per instance (``cooperative_counts``), computed once."""
        return cooperative_counts(self.system)

    @cached_property
    def _spans(self) -> dict[str, Fraction | None]:
        return {}

    @cached_property
    def on_core(self) -> Mapping[str, tuple[TaskModel, ...]]:
        """The tasks of each core, in the system's order (``SystemModel.tasks_on``), computed once."""
        cores: dict[str, list[TaskModel]] = {}
        for task in self.system.tasks:
            cores.setdefault(task.core, []).append(task)
        return {core: tuple(tasks) for core, tasks in cores.items()}

    @cached_property
    def by_priority(self) -> Mapping[tuple[str, int], tuple[TaskModel, ...]]:
        """The tasks of each (core, priority)."""
        groups: dict[tuple[str, int], list[TaskModel]] = {}
        for task in self.system.tasks:
            groups.setdefault((task.core, task.priority), []).append(task)
        return {key: tuple(tasks) for key, tasks in groups.items()}

    @cached_property
    def zero_time(self) -> bool:
        """Whether a job may run for no time (some ``bcet`` is 0): only then does an instant have more than
        one round of releases and dispatch (§2), so that a job may be released at an instant after a
        job of its priority was dispatched at it."""
        return any(task.bcet == 0 for task in self.system.tasks)

    @cached_property
    def order(self) -> Mapping[str, int]:
        """Each task's position in the system (the dispatch order among equal releases, §1)."""
        return {task.id: n for n, task in enumerate(self.system.tasks)}

    def E(self, task: str) -> Fraction | None:  # noqa: N802 - the spec's name
        """Eᵢ: a bound on the time from the start (read) of a job of ``task`` to its completion
        (``start_to_completion``), computed once per task."""
        spans = self._spans
        if task not in spans:
            spans[task] = start_to_completion(self, task)
        return spans[task]


def _total(parts: Iterable[tuple[str, Fraction | None]]) -> Fraction | None:
    values = []
    for _, v in parts:
        if v is None:
            return None
        values.append(v)
    return exact_sum(values)


def summed_term(rule: str, parts: Iterable[tuple[str, Fraction | None]], note: str = "") -> Term:
    """The term of ``rule`` whose value is the sum of ``parts`` (None if a part is unbounded)."""
    return _new_term(rule, _total(parts), tuple(parts), note)


def _le(a: Term, b: Term) -> bool:
    """a is at least as tight as b (unbounded is the loosest)."""
    if a.value is None:
        return b.value is None
    return b.value is None or a.value <= b.value


# ================================================================== per-step rules


def delta_plus(t: Timing, writer: str, k: int) -> Fraction | None:
    """δ⁺ₚ(k): from the completion of a job of p to the arrival of the k-th output counted from it,
    less d⁺: 0 for k = 1, else ``δ⁺ₚ,act(k) + (Rₚ − Bₚ)`` (§7.3)."""
    if k == 1:
        return ZERO
    span, r = t.events[writer].delta_plus(k), t.R(writer)
    return None if span is None or r is None else span + r - t.B(writer)


def first_step(t: Timing, task: str) -> Step:
    """τ₁ samples the stimulus: reaction ``W⁺₁ + R₁`` (§7.2). For the non-reduced data age, τ₁'s
    step adds ``A⁺₁`` (the previous read of τ₁ is at or after the previous release) and, to the best
    case, the least read gap of τ₁ (§7.5)."""
    parts = ((f"W⁺({task})", t.events[task].sampling_wait), (f"R({task})", t.R(task)))
    best = summed_term(BEST, ((f"C⁻({task})", t.bcet(task)),))
    origin = summed_term(ORIGIN, ((f"A⁺({task})", t.events[task].a_max),),
                   f"from the previous read of `{task}`, at most A⁺ before the current job's release")
    gap = summed_term(ORIGIN_BEST, ((f"max(C⁻, A⁻ − (R − C⁻))({task})", read_gap_min(t, task)),),
                "jobs of one task run one after another, and a start lies in [r, r + R − C⁻]")
    return _new_step("first", task, None, task, None, None, summed_term(FIRST, parts), None, best.value, best,
                     origin, gap)


def last_step(t: Timing, task: str) -> Step:
    """τₙ's job completes within Rₙ of the read it starts with: data age ``Rₙ`` (§7.4)."""
    best = summed_term(BEST, (), "counted on the hop that reaches the last task")
    return _new_step("last", task, None, task, None, None, None, summed_term(LAST, ((f"R({task})", t.R(task)),)),
                     ZERO, best, None, None)


def register_reaction(t: Timing, hop: HopModel) -> Term:
    """``d⁺ + W⁺ᵢ + Rᵢ``: the value arrives within d⁺, the next activation of i within W⁺ᵢ, and that
    job (which starts after the arrival, so reads the value or a newer one) completes within Rᵢ."""
    i = hop.reader
    return summed_term(REGISTER, (("d⁺", hop.link.delay_max), (f"W⁺({i})", t.events[i].sampling_wait),
                            (f"R({i})", t.R(i))))


def register_age(t: Timing, hop: HopModel) -> Term:
    """``d⁺ + A⁺ₚ + Rₚ``: a read of i at time s sees at least the output of the last job of p
    released by ``s − Rₚ − d⁺``, and that job was released after ``s − Rₚ − d⁺ − A⁺ₚ``."""
    p = hop.writer
    return summed_term(REGISTER, (("d⁺", hop.link.delay_max), (f"A⁺({p})", t.events[p].a_max), (f"R({p})", t.R(p))))


def trigger_reaction(t: Timing, hop: HopModel, k: int, rule: str) -> Term:
    """``d⁺ + δ⁺ₚ(k) + Rᵢ``: i is released at one of the k arrivals counted from this value's."""
    p, i = hop.writer, hop.reader
    return summed_term(rule, (("d⁺", hop.link.delay_max), (f"δ⁺({p}, {k})", delta_plus(t, p, k)), (f"R({i})", t.R(i))))


def trigger_age(t: Timing, hop: HopModel, k: int) -> Term:
    """``d⁺ + Rₚ``: every job of i is released by an arrival on this port and reads that value or a
    newer one, whatever the prescaler."""
    p = hop.writer
    return summed_term(trigger_rule(k), (("d⁺", hop.link.delay_max), (f"R({p})", t.R(p))))


def cascade_links(system: SystemModel, hop: HopModel, act: Activation, pact: Activation
                  ) -> tuple[LinkModel, tuple[LinkModel, ...]] | None:
    """The shape of an AND join of one cascade (specs/timing.md §7.3, (7.3e)) when ``hop.reader`` is
    activated by ``act`` and ``hop.writer`` by ``pact``: (the connection ``w → p`` that triggers p,
    alone and without a prescaler; the connections into the other members of the AND compound
    ``act``, every one from ``w``), or None. Whether ``w`` is released by time is the caller's to check."""
    if not (isinstance(act, DataTriggered) and act.mode == "and" and isinstance(pact, DataTriggered)
            and pact.mode == "single" and pact.release_every == 1):
        return None
    i, p = system.task(hop.reader), system.task(hop.writer)
    feed = system.link_into(f"{p.instance}.{pact.port}")
    member = hop.link.target.split(".", 1)[1]
    others = tuple(system.link_into(f"{i.instance}.{m}") for m in act.members if m != member)
    kept = tuple(lk for lk in others if lk is not None and feed is not None and lk.writer == feed.writer)
    if feed is None or not others or len(kept) != len(others):
        return None
    return feed, kept


def cascade_in_time(feed: LinkModel, hop: HopModel, others: Iterable[LinkModel], bcet_p: Fraction) -> bool:
    """(7.3e)'s first condition: ``w``'s message reaches every other member no later than the output of
    the job of ``p`` it releases reaches this one (``d⁺ₘ ≤ d⁻ + C⁻ₚ + d⁻``)."""
    return all(lk.delay_max <= feed.delay_min + bcet_p + hop.link.delay_min for lk in others)


def cascade_fresh(t: Timing, hop: HopModel) -> bool:
    """Whether every other member of the AND join is fresh when this hop's value arrives ((7.3e)): the
    shape (``cascade_links``, with ``w`` released by time), ``cascade_in_time``, and the value of
    ``p``'s job released by ``w``'s message before arrives first: ``d⁺ + Rₚ + d⁺ < δ⁻_out(w) + d⁻ₘ``,
    with ``δ⁻_out(w) = max(C⁻_w, a⁻_w − (R_w − B_w))`` the least distance of ``w``'s completions."""
    system = t.system
    p = system.task(hop.writer)
    shape = cascade_links(system, hop, system.task(hop.reader).activation, p.activation)
    if shape is None:
        return False
    feed, others = shape
    w = feed.writer
    R_p, R_w, gaps = t.R(p.id), t.R(w), system.task(w).activation.gaps
    if R_p is None or R_w is None or gaps is None or not cascade_in_time(feed, hop, others, p.bcet):
        return False
    spacing = max(t.bcet(w), gaps[0] - (R_w - t.B(w)))
    return all(feed.delay_max + R_p + hop.link.delay_max < spacing + lk.delay_min for lk in others)


def _and_waits(t: Timing, hop: HopModel, k: int) -> tuple[Fraction | None, Fraction | None]:
    """(``maxₘ W⁺ₘ`` over the arrival streams of the other members of the AND compound that triggers
    ``hop.reader`` — 0 when they are fresh by (7.3e) —, ``δ⁺_AND(k)``); None where a member is
    unconnected or not bounded."""
    info = t.infos[hop.reader]
    member = hop.link.target.split(".", 1)[1]
    arrivals: list[EventModel | None] = []
    waits: list[Fraction | None] = []
    for src in info.sources:
        if src.writer is None or src.link is None:
            arrivals.append(None)
            if src.member != member:
                waits.append(None)
            continue
        model = arrival_model(t.events[src.writer], t.R(src.writer), t.B(src.writer), src.link)
        arrivals.append(model)
        if src.member != member:
            waits.append(model.sampling_wait)
    # (no None in waits or arrivals where they are used: checked)
    known = [w for w in waits if w is not None]
    wait = None if len(known) < len(waits) else max(known, default=ZERO)
    if wait is not None and cascade_fresh(t, hop):
        wait = ZERO
    streams = [a for a in arrivals if a is not None]
    join = None if len(streams) < len(arrivals) else combine_and(streams).delta_plus(k)
    return wait, join


def and_reaction(t: Timing, hop: HopModel, k: int) -> Term:
    """``d⁺ + maxₘ W⁺ₘ + δ⁺_AND(k) + Rᵢ``: after this value arrives, the join fires once every other
    member has a new arrival (each within its arrival stream's W⁺), then k − 1 further joins."""
    wait, join = _and_waits(t, hop, k)
    i = hop.reader
    return summed_term(AND_JOIN, (("d⁺", hop.link.delay_max), ("wait for the other members", wait),
                            (f"δ⁺_AND({k})", join), (f"R({i})", t.R(i))))


def and_age(t: Timing, hop: HopModel, k: int, origin: str) -> Term:
    """Release age over an AND member (specs/timing.md §7.7, (7.7c)): ``d⁺ + Rₚ + maxₘ W⁺ₘ`` (``Eₚ``
    for ``Rₚ`` when p's age is counted from its start). The job of i is released at the event that
    follows the latest arrival x of this member before it within ``maxₘ W⁺ₘ`` of the other members:
    the member is fresh at x (it has a value since the previous event), and every other member is
    fresh once it has a new arrival; i reads x's value or a newer one."""
    p = hop.writer
    wait, _ = _and_waits(t, hop, k)
    writer = {"release": ((f"R({p})", t.R(p)),), "start": ((f"E({p})", t.E(p)),), "finish": ()}[origin]
    note = "the join fires within the other members' W⁺ after this member's latest arrival"
    rule = {"release": AND_AGE, "start": AND_AGE + ", " + READ_AGE, "finish": AND_AGE}[origin]
    if origin == "finish":
        note += f"; `{p}`'s completion is counted in the hop before ({PAIR})"
    return summed_term(rule, (("d⁺", hop.link.delay_max),) + writer + (("wait for the other members", wait),), note)


def trigger_age_from_start(t: Timing, hop: HopModel, k: int) -> Term:
    """``d⁺ + Eₚ`` (specs/timing.md §7.7, (7.7b)): when p's age is counted from its job's start, the
    job that triggers i completes within Eₚ of that start."""
    p = hop.writer
    return summed_term(READ_AGE, (("d⁺", hop.link.delay_max), (f"E({p})", t.E(p))),
                 f"`{hop.reader}` is released by `{p}`'s output, which completes within E of its job's read "
                 f"(its {trigger_rule(k)} term with E for R)")


def trigger_age_from_finish(t: Timing, hop: HopModel, k: int) -> Term:
    """``d⁺``: p's age is counted at its job's completion (after a same-core trigger pair, (7.7d))."""
    return summed_term(trigger_rule(k), (("d⁺", hop.link.delay_max),),
                 f"`{hop.writer}`'s completion is counted in the hop before ({PAIR})")


def pair_qualifies(t: Timing, hop: HopModel) -> bool:
    """Whether hop p → i is a same-core trigger pair (``pair_shape`` with i's activation)."""
    return pair_shape(t.system, hop, t.system.task(hop.reader).activation, t.cooperative_count)


def pair_shape(system: SystemModel, hop: HopModel, act: Activation, cooperative: Mapping[str, int]) -> bool:
    """Whether hop p → i is a same-core trigger pair (specs/timing.md §7.7, (7.7d)) when i is activated
    by ``act``: p and i on one core, i of strictly higher priority, triggered by this in-port alone (any
    prescaler), the delay exactly 0, and i never waits for a token (preemptive, or the only cooperative
    task of its instance). It depends on the model only, like ``same_core_reason``."""
    p, i = system.task(hop.writer), system.task(hop.reader)
    return (p.core == i.core and i.priority > p.priority and hop.link.delay_max == 0
            and isinstance(act, DataTriggered) and act.mode == "single"
            and act.port == hop.link.target.split(".", 1)[1]
            and (i.kind != "cooperative" or cooperative.get(i.instance, 0) <= 1))


def pair_fixed_point(t: Timing, hop: HopModel) -> Fraction | None:
    """The least ``w = C⁺ₚ + C⁺ᵢ + Σⱼ η⁺ⱼ(w)·C⁺ⱼ`` of (7.7d) over the tasks j ≠ i of hp(p) that may run
    while p's job is pending (``overtakes``) or while i's is (priority at least i's); None if none."""
    p, i = t.system.task(hop.writer), t.system.task(hop.reader)
    # a cooperative sibling of p cannot run while p's job holds the token, but may once it completes
    streams = [interferer(t.system, j, t.events[j.id], t.R(j.id), j.wcet)
               for j in t.on_core[p.core] if j.priority >= p.priority and j.id not in (p.id, i.id)
               and (overtakes(t, p, j) or j.priority >= i.priority)]
    value, _ = least_fixed_point(p.wcet + i.wcet, p.wcet + i.wcet, streams)
    return value


def pair_span(t: Timing, hop: HopModel) -> Fraction | None:
    """``Jₚᵢ`` (specs/timing.md §7.7, (7.7d)): from the start of a job of p to the completion of the job of
    i its output releases, ``pair_fixed_point``; None when it is not below ``Eₚ + Rᵢ`` (the two terms it
    replaces) or one of those is unbounded."""
    e, r = t.E(hop.writer), t.R(hop.reader)
    if e is None or r is None:
        return None
    value = pair_fixed_point(t, hop)
    return value if value is not None and value < e + r else None


def pair_age(t: Timing, hop: HopModel) -> Term | None:
    """The same-core trigger pair's term ``Jₚᵢ`` (from p's read to i's completion), or None."""
    if not pair_qualifies(t, hop):
        return None
    span = pair_span(t, hop)
    if span is None:
        return None
    p, i = hop.writer, hop.reader
    return summed_term(PAIR, ((f"J({p}, {i})", span),),
                 f"from the read of `{p}`'s job to the completion of the `{i}` job its output releases: "
                 f"`{i}` outranks `{p}` on their core, so the core is busy with both and what outranks `{p}`")


def last_from_finish(task: str) -> Term:
    """0: τₙ's age is counted at its job's completion (after a same-core trigger pair)."""
    return summed_term(LAST, (), f"`{task}`'s completion is counted in the hop before ({PAIR})")


def last_from_start(t: Timing, task: str) -> Term:
    """``Eₙ`` (specs/timing.md §7.7, (7.7a)): when τₙ's age is counted at its read, its job completes
    within Eₙ of that read."""
    return summed_term(READ_AGE, ((f"E({task})", t.E(task)),),
                 "counted from the last task's read (its start), not its release")


def start_to_completion(t: Timing, task: str) -> Fraction | None:
    """Eᵢ (specs/timing.md §7.7): a bound on the time from the start of a job of ``task`` to its
    completion — the least of Rᵢ, the hold time of §6.3 and the least ``w = C⁺ᵢ + Σ_{j ∈ hp'(i)} η⁺ⱼ(w)·C⁺ⱼ``
    with hp'(i) the tasks of hp(i) that can run while a started job of i is pending (``overtakes``).
    None when none of them is bounded."""
    response = t.responses[task]
    bounds = [v for v in (response.wcrt, response.hold) if v is not None]
    model = t.system.task(task)
    # only a task of i's priority or a cooperative sibling of i can be left out of hp(i); without one,
    # hp'(i) = hp(i) and the fixed point is the hold time
    if bounds and (len(t.by_priority[(model.core, model.priority)]) > 1
                   or (model.kind == "cooperative" and t.cooperative_count.get(model.instance, 0) > 1)):
        hp = [j for j in t.on_core[model.core] if j.priority >= model.priority and j.id != model.id]
        keep = [j for j in hp if overtakes(t, model, j)]
        if len(keep) < len(hp):
            streams = [interferer(t.system, j, t.events[j.id], t.R(j.id), j.wcet) for j in keep]
            value, _ = least_fixed_point(model.wcet, model.wcet, streams)
            if value is not None:
                bounds.append(value)
    return min(bounds) if bounds else None


def overtakes(t: Timing, task: TaskModel, j: TaskModel) -> bool:
    """Whether a job of ``j`` (of hp(i)) may run on i's core between the start of a job of ``task`` and
    its completion (specs/timing.md §7.7). Not when i is cooperative and j a cooperative task of i's
    instance (i holds the token), nor when j has i's priority, never waits for a token (preemptive, or
    the only cooperative task of its instance) and comes after i in the system's order, or is released by
    time (a timer or sporadic source), or no job can run for no time (``Timing.zero_time``): every job of
    j then ranks after a started job of i (§1: a pending one that ranked before it would have started
    instead, and one released later ranks after it — also one released at the same instant, which comes
    before that instant's first dispatch unless a job completing in no time at it triggers it)."""
    if task.kind == "cooperative" and j.kind == "cooperative" and j.instance == task.instance:
        return False
    if task.executor is not None and j.executor == task.executor:
        return False  # a started callback runs to completion in its executor's thread (§9)
    if j.priority != task.priority or (t.order[j.id] < t.order[task.id] and t.zero_time
                                       and not isinstance(j.activation, (Periodic, SporadicSource))):
        return True
    return j.kind == "cooperative" and t.cooperative_count.get(j.instance, 0) > 1


def same_core_reason(system: SystemModel, hop: HopModel, cooperative: Mapping[str, int] | None = None) -> str | None:
    """Why the same-core priority rule (specs/timing.md §7.6, conditions (C1)–(C4)) does not apply to
    ``hop``, or None when it does. It depends on the model only (cores, priorities, task kinds,
    delays), not on rates or response times.

    It needs: writer p and reader i on one core, p's priority strictly higher (equal priorities are
    FIFO, §1, so i may start first), the connection's delay exactly 0 (d⁻ = d⁺ = 0), and p never
    ineligible while i starts: p preemptive, or p the only cooperative task of its instance, or i a
    cooperative task of p's instance (then no sibling holds the token when i starts, §1)."""
    p, i = system.task(hop.writer), system.task(hop.reader)
    if p.core != i.core:
        return "the writer and the reader run on different cores"
    if p.priority <= i.priority:
        return "the writer's priority is not strictly higher than the reader's"
    if hop.link.delay_max != 0:
        return "the connection has a delay"
    if p.kind == "cooperative" and not (i.kind == "cooperative" and i.instance == p.instance):
        count = (cooperative if cooperative is not None else cooperative_counts(system)).get(p.instance, 0)
        if count > 1:
            return "the writer may wait for its instance's cooperative token while the reader starts"
    return None


def same_core_priority(t: Timing, hop: HopModel) -> str | None:
    """``same_core_reason`` with the counts cached in ``t``."""
    return same_core_reason(t.system, hop, t.cooperative_count)


def priority_age(t: Timing, hop: HopModel) -> Term:
    """Data age ``A⁺ₚ`` (Dürr et al., CASES 2019, priority-aware single-core job chains; derived in
    specs/timing.md §7.6, equation (7.6a)). When a job of i released at rᵢ starts (reads) at s ≥ rᵢ,
    every job of p released before that dispatch has completed — the oldest pending one would run
    first — and its output arrived at once (d⁺ = 0), so i reads the output of the last job m of p
    released before it; job m + 1 is released at or after s, within A⁺ₚ of m, so
    ``rᵢ − rₘ ≤ s − rₘ ≤ A⁺ₚ``: the release age grows by at most A⁺ₚ over this hop (§7.1)."""
    p = hop.writer
    return summed_term(SAME_CORE, ((f"A⁺({p})", t.events[p].a_max),),
                 f"d⁺ = 0 and `{p}` has the higher priority on the core: every job of it released "
                 "before the reader's start has completed")


def priority_reaction(t: Timing, hop: HopModel) -> Term:
    """Reaction ``W⁺ᵢ + Rᵢ − Rₚ`` (Dürr et al., CASES 2019; derived in specs/timing.md §7.6,
    equation (7.6b)). The previous steps sum to a bound on ``ρₚ + Rₚ``, ρₚ the release of p's first
    job holding the stamp (every reaction term ends with the R of the task it reaches). The first
    job of i released strictly after ρₚ comes within W⁺ᵢ, starts only once that job of p has
    completed (it would run first), reads its output or a newer one (d⁺ = 0) and completes within
    Rᵢ: this step adds ``W⁺ᵢ + Rᵢ`` to ρₚ, i.e. ``W⁺ᵢ + Rᵢ − Rₚ`` to the previous steps' sum."""
    p, i = hop.writer, hop.reader
    r = t.R(p)
    return summed_term(SAME_CORE, ((f"W⁺({i})", t.events[i].sampling_wait), (f"R({i})", t.R(i)),
                             (f"R({p})", None if r is None else -r)),
                 f"counted from the release of `{p}`'s job, not its completion: `{i}`'s next job "
                 "released after it starts only once that job has completed (d⁺ = 0)")


def tighter(a: Term, b: Term) -> bool:
    """a is strictly tighter than b."""
    return a.value is not None and (b.value is None or a.value < b.value)


def hop_step(t: Timing, hop: HopModel) -> Step:
    """The rule that applies to a hop, chosen by how its reader is activated (§7.3)."""
    act = t.system.task(hop.reader).activation
    member = hop.link.target.split(".", 1)[1]
    register_r, register_a = register_reaction(t, hop), register_age(t, hop)
    reaction, age = register_r, register_a
    if isinstance(act, DataTriggered) and member in act.members:
        k = act.prescaler
        if act.mode == "and":
            candidate = and_reaction(t, hop, k)
        else:
            rule = trigger_rule(k) + (" (OR member)" if act.mode == "or" else "")
            candidate = trigger_reaction(t, hop, k, rule)
        if _le(candidate, register_r):
            reaction = candidate
        else:
            reaction = _new_term(register_r.rule, register_r.value, register_r.parts,
                                 f"tighter here than {candidate.rule} ({fmt_time(candidate.value)})")
        if act.mode == "single":
            age = trigger_age(t, hop, k)
        else:
            age = _new_term(register_a.rule, register_a.value, register_a.parts,
                            "the reader may be released by another member, so this value is read as a register")
    elif isinstance(act, DataTriggered):
        reaction = _new_term(register_r.rule, register_r.value, register_r.parts,
                             f"`{hop.reader}` is triggered by `{act.port}`, not by this port")
    if same_core_priority(t, hop) is None:
        refined_r, refined_a = priority_reaction(t, hop), priority_age(t, hop)
        if tighter(refined_r, reaction):
            reaction = refined_r
        if tighter(refined_a, age):
            age = refined_a
    label = f"{hop.writer} → {hop.reader}"
    best = summed_term(BEST, (("d⁻", hop.link.delay_min), (f"C⁻({hop.reader})", t.bcet(hop.reader))))
    return _new_step("hop", label, hop.writer, hop.reader, hop.link.source, hop.link.target, reaction, age,
                     best.value, best, None, None)


def read_gap_min(t: Timing, task: str) -> Fraction:
    """The least time between two consecutive reads (starts) of ``task``:
    ``max(bcet, A⁻ − (R − bcet))`` — jobs of a task run one after another, and a start lies in
    ``[r, r + R − bcet]``."""
    bcet, a_min, r = t.bcet(task), t.events[task].a_min, t.R(task)
    if a_min is None or r is None:
        return bcet
    return max(bcet, a_min - (r - bcet))
