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

Reaction time is non-reduced (from the stimulus), data age reduced by default (from τ₁'s read,
Günzel et al. 2024); the other variants follow by adding or removing τ₁'s sampling term. Best cases
are ``Σ bcetᵢ + Σ d⁻`` (rule "best case", one term per step). ``None`` means unbounded. Dürr et
al. 2019 and Becker et al. 2017 give the job-chain view these terms are derived from.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property
from collections.abc import Iterable, Mapping

from ..construct import direct_constructor
from ..activations import DataTriggered
from ..model import ChainModel, HopModel, SystemModel
from ..units import fmt_time
from .rates import ActivationInfo, EventModel, arrival_model, combine_and, exact_sum
from .rta import TaskResponse

ZERO = Fraction(0)

REGISTER = "register sampling (Davare)"
FIRST = "first-task sampling"
LAST = "last-task response"
AND_JOIN = "AND join"
SAME_CORE = "same-core priority (Dürr et al. CASES 2019)"
ORIGIN = "non-reduced origin"
BEST = "best case"
ORIGIN_BEST = "least read gap of τ₁"


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
        """The bound of a latency kind as ``verify.sim.KINDS`` names it: "reaction_time",
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


#: the constructors of the objects above, built by the thousand (``verify.construct``)
_new_term = direct_constructor(Term)
_new_step = direct_constructor(Step)
_new_bound = direct_constructor(Bound)
_new_spec_check = direct_constructor(SpecCheck)
_new_chain_bounds = direct_constructor(ChainBounds)


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


def _total(parts: Iterable[tuple[str, Fraction | None]]) -> Fraction | None:
    values = [v for _, v in parts]
    return None if any(v is None for v in values) else exact_sum(values)  # type: ignore[arg-type]  # no None


def _term(rule: str, parts: Iterable[tuple[str, Fraction | None]], note: str = "") -> Term:
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
    best = _term(BEST, ((f"C⁻({task})", t.bcet(task)),))
    origin = _term(ORIGIN, ((f"A⁺({task})", t.events[task].a_max),),
                   f"from the previous read of `{task}`, at most A⁺ before the current job's release")
    gap = _term(ORIGIN_BEST, ((f"max(C⁻, A⁻ − (R − C⁻))({task})", read_gap_min(t, task)),),
                "jobs of one task run one after another, and a start lies in [r, r + R − C⁻]")
    return _new_step("first", task, None, task, None, None, _term(FIRST, parts), None, best.value, best,
                     origin, gap)


def last_step(t: Timing, task: str) -> Step:
    """τₙ's job completes within Rₙ of the read it starts with: data age ``Rₙ`` (§7.4)."""
    best = _term(BEST, (), "counted on the hop that reaches the last task")
    return _new_step("last", task, None, task, None, None, None, _term(LAST, ((f"R({task})", t.R(task)),)),
                     ZERO, best, None, None)


def register_reaction(t: Timing, hop: HopModel) -> Term:
    """``d⁺ + W⁺ᵢ + Rᵢ``: the value arrives within d⁺, the next activation of i within W⁺ᵢ, and that
    job (which starts after the arrival, so reads the value or a newer one) completes within Rᵢ."""
    i = hop.reader
    return _term(REGISTER, (("d⁺", hop.link.delay_max), (f"W⁺({i})", t.events[i].sampling_wait),
                            (f"R({i})", t.R(i))))


def register_age(t: Timing, hop: HopModel) -> Term:
    """``d⁺ + A⁺ₚ + Rₚ``: a read of i at time s sees at least the output of the last job of p
    released by ``s − Rₚ − d⁺``, and that job was released after ``s − Rₚ − d⁺ − A⁺ₚ``."""
    p = hop.writer
    return _term(REGISTER, (("d⁺", hop.link.delay_max), (f"A⁺({p})", t.events[p].a_max), (f"R({p})", t.R(p))))


def trigger_reaction(t: Timing, hop: HopModel, k: int, rule: str) -> Term:
    """``d⁺ + δ⁺ₚ(k) + Rᵢ``: i is released at one of the k arrivals counted from this value's."""
    p, i = hop.writer, hop.reader
    return _term(rule, (("d⁺", hop.link.delay_max), (f"δ⁺({p}, {k})", delta_plus(t, p, k)), (f"R({i})", t.R(i))))


def trigger_age(t: Timing, hop: HopModel, k: int) -> Term:
    """``d⁺ + Rₚ``: every job of i is released by an arrival on this port and reads that value or a
    newer one, whatever the prescaler."""
    p = hop.writer
    return _term(trigger_rule(k), (("d⁺", hop.link.delay_max), (f"R({p})", t.R(p))))


def and_reaction(t: Timing, hop: HopModel, k: int) -> Term:
    """``d⁺ + maxₘ W⁺ₘ + δ⁺_AND(k) + Rᵢ``: after this value arrives, the join fires once every other
    member has a new arrival (each within its arrival stream's W⁺), then k − 1 further joins."""
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
    wait = None if any(w is None for w in waits) else max(waits, default=ZERO)  # type: ignore[type-var]
    join = None if any(a is None for a in arrivals) else combine_and(arrivals).delta_plus(k)  # type: ignore[arg-type]
    i = hop.reader
    return _term(AND_JOIN, (("d⁺", hop.link.delay_max), ("wait for the other members", wait),
                            (f"δ⁺_AND({k})", join), (f"R({i})", t.R(i))))


def cooperative_counts(system: SystemModel) -> dict[str, int]:
    """The number of cooperative tasks per instance (a token is shared where there are two)."""
    count: dict[str, int] = {}
    for task in system.tasks:
        if task.kind == "cooperative":
            count[task.instance] = count.get(task.instance, 0) + 1
    return count


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
    return _term(SAME_CORE, ((f"A⁺({p})", t.events[p].a_max),),
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
    return _term(SAME_CORE, ((f"W⁺({i})", t.events[i].sampling_wait), (f"R({i})", t.R(i)),
                             (f"R({p})", None if r is None else -r)),
                 f"counted from the release of `{p}`'s job, not its completion: `{i}`'s next job "
                 "released after it starts only once that job has completed (d⁺ = 0)")


def _tighter(a: Term, b: Term) -> bool:
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
        if _tighter(refined_r, reaction):
            reaction = refined_r
        if _tighter(refined_a, age):
            age = refined_a
    label = f"{hop.writer} → {hop.reader}"
    best = _term(BEST, (("d⁻", hop.link.delay_min), (f"C⁻({hop.reader})", t.bcet(hop.reader))))
    return _new_step("hop", label, hop.writer, hop.reader, hop.link.source, hop.link.target, reaction, age,
                     best.value, best, None, None)


# ================================================================== chain totals


def _sum_terms(terms: list[Term]) -> Fraction | None:
    values = [x.value for x in terms]
    return None if any(v is None for v in values) else exact_sum(values)  # type: ignore[arg-type]  # no None


def reaction_time(steps: tuple[Step, ...]) -> Fraction | None:
    """Non-reduced reaction time: ``W⁺₁ + R₁ + Σ_hops reaction terms`` (§7.5)."""
    return _sum_terms([s.reaction for s in steps if s.reaction is not None])


def data_age(steps: tuple[Step, ...]) -> Fraction | None:
    """Reduced data age: ``Σ_hops data-age terms + Rₙ`` (§7.5)."""
    return _sum_terms([s.data_age for s in steps if s.data_age is not None])


def _minus(a: Fraction | None, b: Fraction | None) -> Fraction | None:
    return None if a is None or b is None else a - b


def _dominating(steps: tuple[Step, ...], *attrs: str) -> int | None:
    """The step whose term (the sum of its ``attrs`` terms) is largest; an unbounded one dominates."""
    best, index = None, None
    for n, step in enumerate(steps):
        terms = [getattr(step, attr) for attr in attrs if getattr(step, attr) is not None]
        if not terms:
            continue
        if any(term.value is None for term in terms):
            return n
        value = exact_sum(term.value for term in terms)
        if best is None or value > best:
            best, index = value, n
    return index


def data_age_non_reduced(steps: tuple[Step, ...]) -> Fraction | None:
    """Non-reduced data age: the reduced one plus τ₁'s ``A⁺₁`` (§7.5)."""
    return _sum_terms([x for s in steps for x in (s.data_age, s.data_age_non_reduced) if x is not None])


def read_gap_min(t: Timing, task: str) -> Fraction:
    """The least time between two consecutive reads (starts) of ``task``:
    ``max(bcet, A⁻ − (R − bcet))`` — jobs of a task run one after another, and a start lies in
    ``[r, r + R − bcet]``."""
    bcet, a_min, r = t.bcet(task), t.events[task].a_min, t.R(task)
    if a_min is None or r is None:
        return bcet
    return max(bcet, a_min - (r - bcet))


def chain_bounds(t: Timing, chain: ChainModel, variant: str = "reduced") -> ChainBounds:
    """Every bound of ``chain`` with its per-step breakdown and its margins (§7)."""
    missing = [x for x in chain.tasks if x not in t.responses]
    if missing or not chain.tasks or len(chain.hops) != len(chain.tasks) - 1:
        return _broken(chain, variant, f"the chain refers to unknown tasks {missing}" if missing
                       else "the chain's hops do not match its tasks")
    first, last = chain.tasks[0], chain.tasks[-1]
    steps = (first_step(t, first),) + tuple(hop_step(t, h) for h in chain.hops) + (last_step(t, last),)
    best = exact_sum(s.best for s in steps)
    wait = t.events[first].sampling_wait
    reaction = reaction_time(steps)
    bounds = dict(
        reaction_time=_new_bound(reaction, best, "§7.5 W⁺₁ + R₁ + Σ hop reaction terms"),
        reaction_time_reduced=_new_bound(_minus(reaction, wait), best, "§7.5 R₁ + Σ hop reaction terms"),
        data_age_reduced=_new_bound(data_age(steps), best, "§7.5 Σ hop data-age terms + Rₙ"),
        # τ₁'s step has best_non_reduced, with a value (``first_step``, ``read_gap_min``)
        data_age_non_reduced=_new_bound(data_age_non_reduced(steps),
                                        best + steps[0].best_non_reduced.value,  # type: ignore[union-attr, operator]
                                        "§7.5 A⁺₁ + Σ hop data-age terms + Rₙ"),
    )
    specs = _spec_checks(chain, bounds, variant)
    return _new_chain_bounds(chain.name, chain.tasks, steps, data_age_variant=variant, specs=specs,
                             dominating_reaction=_dominating(steps, "reaction"),
                             dominating_data_age=_dominating(steps, "data_age"),
                             dominating_data_age_non_reduced=_dominating(steps, "data_age",
                                                                         "data_age_non_reduced"), **bounds)


def _spec_checks(chain: ChainModel, bounds: dict[str, Bound], variant: str) -> tuple[SpecCheck, ...]:
    age = bounds["data_age_reduced" if variant == "reduced" else "data_age_non_reduced"]
    checks = []
    if chain.reaction_time is not None:
        checks.append(_new_spec_check("reaction_time", chain.reaction_time, bounds["reaction_time"].worst,
                                      "non-reduced"))
    if chain.data_age is not None:
        checks.append(_new_spec_check("data_age", chain.data_age, age.worst, variant))
    if chain.jitter is not None:
        checks.append(_new_spec_check("jitter", chain.jitter, age.jitter, f"data age ({variant})"))
    return tuple(checks)


def _broken(chain: ChainModel, variant: str, problem: str) -> ChainBounds:
    unknown = _new_bound(None, ZERO, "not analysed")
    bounds = dict(reaction_time=unknown, reaction_time_reduced=unknown, data_age_reduced=unknown,
                  data_age_non_reduced=unknown)
    return _new_chain_bounds(chain.name, chain.tasks, (), data_age_variant=variant,
                             specs=_spec_checks(chain, bounds, variant), dominating_reaction=None,
                             dominating_data_age=None, dominating_data_age_non_reduced=None, problem=problem,
                             **bounds)
