"""Proof obligations and their verdicts by the compositional bound (specs/proof.md §2).

Every chain spec and every task deadline of a configured system is one ``Obligation``: the number
asked for, the analysis' bound (specs/timing.md §6–§7) and what the exact search would measure
(a ``Target``). An obligation whose bound meets the spec is proved by the bound; the rest go to the
exact search.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TypedDict, Unpack
from collections.abc import Mapping, Sequence

from ..core.construct import direct_constructor
from ..model.system import SystemModel
from ..core.source import NO_SPAN, Span
from ..timing import ChainBounds, TaskResponse
from .scenario import Target
from .verdict import Counterexample, Verdict, sim_kind


class VerdictExtra(TypedDict, total=False):
    """What a verdict may add to its obligation (the optional fields of ``Verdict``)."""

    exact: Fraction | None
    exact_best: Fraction | None
    refined: Fraction | None
    counterexample: Counterexample | None
    note: str
    explored: int


@dataclass(frozen=True)
class Obligation:
    subject: str  # "chain" | "task"
    name: str
    kind: str  # "reaction_time" | "data_age" | "jitter" | "deadline"
    spec: Fraction
    bound: Fraction | None
    target: Target
    variant: str
    span: Span = NO_SPAN
    related: tuple[tuple[Span, str], ...] = ()
    rule: str = ""

    @property
    def proved_by_bound(self) -> bool:
        return self.bound is not None and self.bound <= self.spec

    def verdict(self, status: str, method: str, **extra: Unpack[VerdictExtra]) -> Verdict:
        return _new_verdict(self.subject, self.name, self.kind, self.spec, status, method, self.bound,
                            variant=self.variant, span=self.span, related=self.related, **extra)


_new_verdict = direct_constructor(Verdict)
_new_obligation = direct_constructor(Obligation)
_new_target = direct_constructor(Target)


def obligations(model: SystemModel, variant: str, responses: Mapping[str, TaskResponse],
                chains: Sequence[ChainBounds]) -> list[Obligation]:
    """Chain specs in system order, then task deadlines in task order, from the analysis' bounds
    (``timing.response_and_chain_bounds``: the data-age variant, the responses and the chain bounds)."""
    out: list[Obligation] = []
    by_name = {c.name: c for c in chains}
    for chain in model.chains:
        bounds = by_name[chain.name]
        related = tuple((hop.link.span, f"hop {n}: {hop.link.source} -> {hop.link.target}")
                        for n, hop in enumerate(chain.hops, 1))
        for check in bounds.specs:
            kind = sim_kind(check.kind, variant)
            out.append(_new_obligation("chain", chain.name, check.kind, check.spec, check.bound,
                                       _new_target(kind, chain.name),
                                       "non-reduced" if check.kind == "reaction_time" else variant,
                                       chain.spec_span(check.kind, chain.span), related))
    for task in model.tasks:
        r = responses[task.id]
        if r.deadline is None:
            continue
        out.append(_new_obligation("task", task.id, "deadline", r.deadline, r.wcrt,
                                   _new_target("response", task.id), "", task.span, (), r.deadline_rule))
    return out


def by_bound(ob: Obligation) -> Verdict:
    return ob.verdict("proved", "bound")
