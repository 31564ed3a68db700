"""Timing analysis of a configured system (specs/timing.md §5–§7): rates, response times, chains.

    result = analyze(system)                 # never raises on unschedulable input
    result.task("laser.LaserTask").wcrt      # Fraction seconds, or None: unbounded
    result.chain("reactive").reaction_time.worst
    diagnostics_of(result)                   # E305/E306, E310, E311, E312

Response times and the activation models of data-triggered tasks depend on each other (a triggered
task inherits its writer's response-time jitter, and jitter raises interference), so the analysis
iterates to the global fixed point of compositional performance analysis (Richter 2005; Henia et
al. 2005): start with every response time at its best case (no jitter), compute event models, run
the response-time analysis, repeat until nothing changes. Results are frozen dataclasses and never
refer back into the model by mutation. ``None`` stands for "unbounded" everywhere.
"""
from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

from ..core.construct import direct_constructor
from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..core.gcpause import paused_gc
from ..model.arrivals import with_arrivals
from ..model.system import SystemModel, TaskModel

if TYPE_CHECKING:  # (imported when first used: `verify check` needs the rates alone, not the analysis)
    from . import fastrta
    from .chains import Bound, ChainBounds, SpecCheck, Step, Term, Timing
    from .rates import ActivationInfo, EventModel, LinkSampling, RateInterval
    from .kernel import TaskResponse
    from .reference import response_times  # noqa: F401 - the reference statement of one round, importable as before
    from .rta import CoreLoad

#: the names this package gives from its modules, each imported at its first use (PEP 562)
_FROM_MODULES = {**dict.fromkeys(("Bound", "ChainBounds", "SpecCheck", "Step", "Term", "Timing"), "chains"),
                 **dict.fromkeys(("ActivationInfo", "EventModel", "LinkSampling", "RateInterval"), "rates"),
                 "TaskResponse": "kernel", "response_times": "reference", "CoreLoad": "rta"}


def __getattr__(name: str) -> object:
    """A name of ``_FROM_MODULES``, imported from its module at its first use."""
    module = _FROM_MODULES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


__all__ = ["ActivationInfo", "AnalysisResult", "Bound", "ChainBounds", "CoreLoad", "EventModel",
           "LinkSampling", "RateInterval", "SpecCheck", "Step", "TaskResponse", "TaskTiming", "Term",
           "analyze", "diagnostics_of", "response_and_chain_bounds", "timing_of"]

MAX_ROUNDS = 200  # CPA global iterations before reporting non-convergence
VARIANTS = ("reduced", "non-reduced")


@dataclass(frozen=True)
class TaskTiming:
    """Everything the analysis knows about one task."""

    id: str
    core: str
    priority: int
    kind: str  # "preemptive" | "cooperative"
    bcet: Fraction
    wcet: Fraction
    activation: ActivationInfo
    events: EventModel
    response: TaskResponse
    executor: str | None = None  # the ROS 2 executor running it as a callback (specs/timing.md §9)

    @property
    def rate(self) -> RateInterval | None:
        return self.activation.rate

    @property
    def a_max(self) -> Fraction | None:
        """A⁺: the longest time between consecutive activations."""
        return self.events.a_max

    @property
    def a_min(self) -> Fraction | None:
        """A⁻: the shortest time between consecutive activations."""
        return self.events.a_min

    @property
    def sampling_wait(self) -> Fraction | None:
        """W⁺ = max(A⁺, latest first activation)."""
        return self.events.sampling_wait

    @property
    def wcrt(self) -> Fraction | None:
        return self.response.wcrt

    @property
    def bcrt(self) -> Fraction:
        return self.response.bcrt


_new_task_timing = direct_constructor(TaskTiming)  # (``verify.core.construct``: one per task)


@dataclass(frozen=True)
class AnalysisResult:
    """The analysis of one system. ``converged`` is False if the CPA iteration hit ``MAX_ROUNDS``
    (the tasks still changing are then reported unbounded, E312)."""

    system: str
    data_age_variant: str
    tasks: tuple[TaskTiming, ...]
    cores: tuple[CoreLoad, ...]
    links: tuple[LinkSampling, ...]
    chains: tuple[ChainBounds, ...]
    diagnostics: tuple[Diagnostic, ...]
    rounds: int
    converged: bool

    def task(self, task_id: str) -> TaskTiming:
        return next(t for t in self.tasks if t.id == task_id)

    def chain(self, name: str) -> ChainBounds:
        return next(c for c in self.chains if c.name == name)

    def core(self, name: str) -> CoreLoad:
        return next(c for c in self.cores if c.core == name)

    def sampling(self, target: str, reader: str | None = None) -> LinkSampling:
        """The sampling relation of the connection into in-port ``target`` (for ``reader``)."""
        return next(s for s in self.links if s.target == target and (reader is None or s.reader == reader))


def analyze(system: SystemModel, *, data_age: str = "reduced") -> AnalysisResult:
    """Analyse a configured system. ``data_age`` selects the variant checked against ``data_age`` and
    ``jitter`` specs: "reduced" (from the first task's read, the default) or "non-reduced"."""
    variant = _variant(data_age)
    with paused_gc():
        return _analyze(with_arrivals(system), variant)


def response_and_chain_bounds(system: SystemModel, *, data_age: str = "reduced"
                              ) -> tuple[str, dict[str, TaskResponse], tuple[ChainBounds, ...]]:
    """The part of ``analyze`` that proofs by bound need: (data-age variant, every task's
    ``TaskResponse`` by id, every chain's ``ChainBounds``), computed as ``analyze`` computes them, without
    the sampling relations, core loads, per-task summaries and diagnostics."""
    variant = _variant(data_age)
    with paused_gc():
        _, _, responses, chains, _, _ = _bounds(with_arrivals(system), variant)
        return variant, responses, chains


def timing_of(result: AnalysisResult, system: SystemModel) -> Timing:
    """What the chain rules read (``Timing``), rebuilt from an analysis of ``system``: to evaluate a
    rule's quantity for the analysed configuration, e.g. the start-to-completion time ``E`` of §7.7
    that synthesis learns lemmas from."""
    from .chains import Timing

    return Timing(with_arrivals(system), {t.id: t.activation for t in result.tasks},
                  {t.id: t.events for t in result.tasks}, {t.id: t.response for t in result.tasks})


def _variant(data_age: str) -> str:
    variant = data_age.replace("_", "-")
    if variant not in VARIANTS:
        raise ValueError(f"data_age must be one of {VARIANTS}, not {data_age!r}")
    return variant


def _bounds(system: SystemModel, variant: str
            ) -> tuple[dict[str, ActivationInfo], dict[str, EventModel], dict[str, TaskResponse],
                       tuple[ChainBounds, ...], int, bool]:
    """Rates, event models, response times (the CPA fixed point) and chain bounds: (infos, events,
    responses, chains, rounds, converged)."""
    from .chains import Timing
    from .endtoend import chain_bounds
    from .rates import activation_rates, trigger_order

    order = trigger_order(system)
    infos = activation_rates(system, order)
    events, responses, rounds, converged = _fixed_point(system, infos, order[0])
    timing = Timing(system, infos, events, responses)
    chains = tuple(chain_bounds(timing, c, variant) for c in system.chains)
    return infos, events, responses, chains, rounds, converged


def _analyze(system: SystemModel, variant: str) -> AnalysisResult:
    from .rates import check_sampling, check_trigger_constraints, sampling_relations
    from .rta import check_response_times, check_utilisation, core_loads

    sink = DiagnosticSink()
    infos, events, responses, chains, rounds, converged = _bounds(system, variant)
    loads = core_loads(system, infos)
    samplings = sampling_relations(system, infos)
    check_trigger_constraints(system, infos, sink)
    check_sampling(system, samplings, sink)
    check_utilisation(system, loads, infos, sink)
    check_response_times(system, responses, sink)
    tasks = tuple(_task_timing(t, infos[t.id], events[t.id], responses[t.id]) for t in system.tasks)
    return AnalysisResult(system.name, variant, tasks, loads, samplings, chains,
                          tuple(sorted(sink.items, key=Diagnostic.sort_key)), rounds, converged)


def diagnostics_of(result: AnalysisResult) -> list[Diagnostic]:
    """The diagnostics of an analysis, sorted by location."""
    return list(result.diagnostics)


def _task_timing(task: TaskModel, info: ActivationInfo, events: EventModel, response: TaskResponse) -> TaskTiming:
    return _new_task_timing(task.id, task.core, task.priority, task.kind, task.bcet, task.wcet, info, events,
                            response, task.executor)


def _fixed_point(system: SystemModel, infos: Mapping[str, ActivationInfo], order: tuple[str, ...]
                 ) -> tuple[dict[str, EventModel], dict[str, TaskResponse], int, bool]:
    """CPA global iteration: event models from response times, response times from event models,
    starting from R = bcet (zero jitter) until the WCRTs repeat (§6.5). Each round is
    ``reference.response_times``, computed by ``fastrta``; only the last one's ``TaskResponse``s are built."""
    from . import fastrta
    from .rates import event_models

    static = fastrta.Static(system)
    bcrt: dict[str, Fraction] = {t.id: t.bcet for t in system.tasks}
    wcrt: dict[str, Fraction | None] = {t.id: (t.wcrt_bound if t.wcrt_bound is not None else t.bcet)
                                        for t in system.tasks}
    memo: dict[str, object] = {}  # (``event_models``' own, kept across rounds)
    analysed: fastrta.Round | None = None
    for rounds in range(1, MAX_ROUNDS + 1):
        events = event_models(system, infos, order, wcrt, bcrt, memo)
        analysed = fastrta.Round(static, events, wcrt, analysed)
        analysed.previous = None  # (only one round back is needed)
        new = analysed.wcrts()
        if new == wcrt:
            return events, analysed.responses(), rounds, True
        wcrt = new
    return _give_up(system, infos, order, wcrt, None, bcrt, static)


def _give_up(system: SystemModel, infos: Mapping[str, ActivationInfo], order: tuple[str, ...],
             wcrt: dict[str, Fraction | None], responses: dict[str, TaskResponse] | None,
             bcrt: Mapping[str, Fraction], static: fastrta.Static
             ) -> tuple[dict[str, EventModel], dict[str, TaskResponse], int, bool]:
    """Non-convergence (E312): every task whose WCRT still changes is made unbounded (None absorbs),
    and the rest is recomputed until nothing changes; at most one more round per task."""
    from . import fastrta
    from .rates import event_models

    forced: set[str] = set()
    for _ in range(len(system.tasks) + 1):
        events = event_models(system, infos, order, wcrt, bcrt)
        responses = {tid: (_unbounded(r) if tid in forced else r)
                     for tid, r in fastrta.response_times(system, events, wcrt, static).items()}
        changed = {tid for tid, r in responses.items() if r.wcrt != wcrt[tid]}
        if not changed:
            break
        forced |= changed
        wcrt = {tid: (None if tid in forced else r.wcrt) for tid, r in responses.items()}
    assert responses is not None  # (the loop runs at least once)
    return events, responses, MAX_ROUNDS, not forced


def _unbounded(r: TaskResponse) -> TaskResponse:
    from .kernel import TaskResponse

    return TaskResponse(r.task, r.core, r.priority, r.bcrt, None, None, "unbounded", r.deadline,
                        r.deadline_rule, r.blocking, r.hold, r.busy_jobs, r.critical_job, r.interferers,
                        f"the global CPA iteration did not converge within {MAX_ROUNDS} rounds")
