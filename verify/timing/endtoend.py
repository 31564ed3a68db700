"""The end-to-end bounds of a chain (specs/timing.md §7.5, §7.7): the per-step terms of ``chains``
summed into the reaction time and the data age (reduced and non-reduced) with their best cases and
dominating steps, the chain's specs checked against them, and the data age by the three ages of each
task's job — at its release, at its read (start) and at its completion — where that sum is smaller.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction

from ..core.construct import direct_constructor
from ..model.activations import DataTriggered
from ..model.system import ChainModel, HopModel
from .chains import (LAST, ORIGIN, REGISTER, SAME_CORE, ZERO, Bound, ChainBounds, SpecCheck, Step, Term, Timing,
                     and_age, first_step, hop_step, last_from_finish, last_from_start, last_step, pair_age,
                     priority_age, register_age, same_core_priority, summed_term, tighter, trigger_age,
                     trigger_age_from_finish, trigger_age_from_start)
from .multithreaded import may_overlap
from .rates import exact_sum

#: the constructors of the results, built by the thousand (``verify.core.construct``)
_new_bound = direct_constructor(Bound)
_new_spec_check = direct_constructor(SpecCheck)
_new_chain_bounds = direct_constructor(ChainBounds)


# ================================================================== read-time ages (§7.7)


@dataclass(frozen=True)
class HopAges:
    """The data-age terms of one hop p → i by the ages they connect (specs/timing.md §7.7), each None
    where it does not apply: ``read`` bounds i's age at its read (start) given p's release age (register,
    same-core priority; valid from every age of p, all of which bound its release age);
    ``release_from_*`` i's release age given p's age at its release, read or completion (data trigger,
    AND join age); ``pair`` i's age at its completion given p's age at its read (same-core trigger pair)."""

    read: Term
    release_from_release: Term | None
    release_from_start: Term | None
    release_from_finish: Term | None
    pair: Term | None


def hop_ages(t: Timing, hop: HopModel, step: Step) -> HopAges:
    """The terms of one hop for ``read_time_ages``; ``step`` is the hop's step of §7.3/§7.6, whose
    data-age term is reused (with its note) where it is a bound at the read."""
    act = t.system.task(hop.reader).activation
    member = hop.link.target.split(".", 1)[1]
    if step.data_age is not None and step.data_age.rule in (REGISTER, SAME_CORE):
        read = step.data_age
    else:
        read = register_age(t, hop)
        if same_core_priority(t, hop) is None:
            refined = priority_age(t, hop)
            if tighter(refined, read):
                read = refined
    from_release = from_start = from_finish = None
    if isinstance(act, DataTriggered) and member in act.members:
        k = act.prescaler
        if act.mode == "single":
            from_release, from_start = trigger_age(t, hop, k), trigger_age_from_start(t, hop, k)
            from_finish = trigger_age_from_finish(t, hop, k)
        elif act.mode == "and":
            from_release, from_start, from_finish = (and_age(t, hop, k, "release"), and_age(t, hop, k, "start"),
                                                     and_age(t, hop, k, "finish"))
    return HopAges(read, from_release, from_start, from_finish, pair_age(t, hop))


_Path = tuple[Fraction | None, tuple[Term, ...]]


def _extend(path: _Path | None, term: Term | None) -> _Path | None:
    if path is None or term is None:
        return None
    value = None if path[0] is None or term.value is None else path[0] + term.value
    return value, path[1] + (term,)


def _lt(a: _Path | None, b: _Path | None) -> bool:
    """a is strictly tighter than b (a missing path is the loosest, then an unbounded one)."""
    if a is None or a[0] is None:
        return False
    return b is None or b[0] is None or a[0] < b[0]


def _least(*paths: _Path | None) -> _Path | None:
    """The tightest path; the first among equals."""
    best: _Path | None = None
    for path in paths:
        if path is not None and (best is None or _lt(path, best)):
            best = path
    return best


def read_time_ages(t: Timing, chain: ChainModel, hops: list[HopAges], from_read: bool) -> _Path | None:
    """The reduced data age by the three ages of §7.7 — of each task's job at its release, at its read
    (start) and at its completion — starting from τ₁'s age at its release (``from_read`` False) or at its
    read (True), both 0 for the reduced data age (τ₁'s stamp is its read): (bound, the data-age terms of
    the hops and of the last step) along the least sum of terms; None if that start reaches no bound."""
    empty: _Path = (ZERO, ())
    release: _Path | None = None if from_read else empty
    start: _Path | None = empty if from_read else None
    finish: _Path | None = None
    for ages in hops:
        new_start = _extend(_least(release, start, finish), ages.read)
        new_finish = _extend(start, ages.pair)
        release = _least(_extend(release, ages.release_from_release), new_start,
                         _extend(start, ages.release_from_start), _extend(finish, ages.release_from_finish))
        start, finish = new_start, new_finish
    last = chain.tasks[-1]
    return _least(_extend(release, summed_term(LAST, ((f"R({last})", t.R(last)),))),
                  _extend(start, last_from_start(t, last)), _extend(finish, last_from_finish(last)))


# ================================================================== chain totals


def _sum_terms(terms: list[Term]) -> Fraction | None:
    values = [v for x in terms if (v := x.value) is not None]
    return None if len(values) < len(terms) else exact_sum(values)


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


def chain_bounds(t: Timing, chain: ChainModel, variant: str = "reduced") -> ChainBounds:
    """Every bound of ``chain`` with its per-step breakdown and its margins (§7)."""
    missing = [x for x in chain.tasks if x not in t.responses]
    if missing or not chain.tasks or len(chain.hops) != len(chain.tasks) - 1:
        return _broken(chain, variant, f"the chain refers to unknown tasks {missing}" if missing
                       else "the chain's hops do not match its tasks")
    overlapping = [x for x in chain.tasks if may_overlap(t.system, t.system.task(x), t.R(x), t.events[x])]
    if overlapping:
        return _broken(chain, variant, f"`{overlapping[0]}` may run two jobs at once and complete them out of "
                       "order (a reentrant callback group of a multi-threaded executor, specs/timing.md §9.4)")
    first, last = chain.tasks[0], chain.tasks[-1]
    steps = (first_step(t, first),) + tuple(hop_step(t, h) for h in chain.hops) + (last_step(t, last),)
    steps = _with_read_time_ages(t, chain, steps)
    best = exact_sum(s.best for s in steps)
    wait = t.events[first].sampling_wait
    reaction = reaction_time(steps)
    origin = steps[0].best_non_reduced  # τ₁'s step has it, with a value (``first_step``, ``read_gap_min``)
    bounds = dict(
        reaction_time=_new_bound(reaction, best, "§7.5 W⁺₁ + R₁ + Σ hop reaction terms"),
        reaction_time_reduced=_new_bound(_minus(reaction, wait), best, "§7.5 R₁ + Σ hop reaction terms"),
        data_age_reduced=_new_bound(data_age(steps), best, "§7.5 Σ hop data-age terms + Rₙ"),
        data_age_non_reduced=_new_bound(data_age_non_reduced(steps),
                                        best if origin is None or origin.value is None else best + origin.value,
                                        "§7.5 A⁺₁ + Σ hop data-age terms + Rₙ"),
    )
    specs = _spec_checks(chain, bounds, variant)
    return _new_chain_bounds(chain.name, chain.tasks, steps, data_age_variant=variant, specs=specs,
                             dominating_reaction=_dominating(steps, "reaction"),
                             dominating_data_age=_dominating(steps, "data_age"),
                             dominating_data_age_non_reduced=_dominating(steps, "data_age",
                                                                         "data_age_non_reduced"), **bounds)


def _with_read_time_ages(t: Timing, chain: ChainModel, steps: tuple[Step, ...]) -> tuple[Step, ...]:
    """``steps`` with the data-age terms of ``read_time_ages`` where their sum is strictly smaller than
    that of the terms of §7.3–§7.4 (so the report changes only where the bound does).

    The non-reduced data age counts from τ₁'s previous read, at most ``A⁺₁`` before τ₁'s release and
    at most ``A⁺₁ + R₁ − C⁻₁`` before its read (§7.7): when the terms counted from τ₁'s read are the
    tighter reduced bound, τ₁'s non-reduced term adds the least of ``R₁ − C⁻₁`` and the excess of the
    terms counted from its release."""
    hops = [hop_ages(t, hop, step) for hop, step in zip(chain.hops, steps[1:])]
    from_release, from_read = read_time_ages(t, chain, hops, False), read_time_ages(t, chain, hops, True)
    best = from_read if _lt(from_read, from_release) else from_release
    current = data_age(steps)
    if best is None or best[0] is None or (current is not None and best[0] >= current):
        return steps
    first, value = steps[0], best[0]
    if best is from_read:
        task = first.reader
        r = t.R(task)
        gap = None if r is None else r - t.bcet(task)
        excess = None if from_release is None or from_release[0] is None else from_release[0] - value
        extra: tuple[str, Fraction | None]
        if excess is not None and (gap is None or excess < gap):
            extra = ("terms counted from its release − these terms", excess)
            note = (f"from the previous read of `{task}`, at most A⁺ before the current job's release: the "
                    "terms counted from the release exceed these (counted from its read) by the second part")
        else:
            extra = (f"R({task}) − C⁻({task})", gap)
            note = f"from the previous read of `{task}`, at most A⁺ + R − C⁻ before the current job's read"
        origin = summed_term(ORIGIN, ((f"A⁺({task})", t.events[task].a_max), extra), note)
        first = replace(first, data_age_non_reduced=origin)
    ages = iter(best[1])
    return (first,) + tuple(replace(step, data_age=next(ages)) for step in steps[1:])


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
