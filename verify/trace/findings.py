"""Measurements held against the model, as located diagnostics (specs/trace.md §4).

- E801 (error): a task's measured execution time (the CPU time its job records give, else end − start)
  above its ``wcet`` — the bounds do not hold for this robot; at the ``wcet``;
- E802 (error): a timer's period off the model — registered with another period, or its mean measured
  period off by more than the tolerance; at the activation;
- E804 (error): a chain's measured reaction time, data age or jitter above its spec; at the spec;
- E803 (warning, an alarm): a measured latency above its bound but within its spec — the bound rests on
  an assumption the robot broke, and the message names it: a task of the chain above its ``wcet``, a
  timer off its period, a connection above its ``delay``, a task whose jobs took longer than the
  ``wcet`` from start to finish within it of CPU time (other work took the CPU from them), else the
  connections' delays and the executors' order the model assumed;
- E805 (warning): a task of the model without a callback in the trace, or a callback of an instance of
  the model without a task (listed, never guessed); at the task, or the instance;
- E806: a trace that cannot be read (error), or that is read in part (warning: what was read stands);
- E807 (warning, an alarm; ``delays.py``): a connection's measured delay above its ``delay``.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from ..model import syntax as s
from ..core.diagnostics import DiagnosticSink, Label, Severity
from ..interop.caret.to_vfy import language_name
from ..frontend.loader import Project
from ..model.activations import Periodic
from ..model.system import ChainModel, SystemModel
from ..core.source import NO_SPAN, Span
from ..timing import AnalysisResult
from ..model.units import fmt_time
from .match import Matching
from .delays import Delays
from .metrics import Distribution, Measurements, TaskMeasure
from .recording import Recording

#: how far a timer's mean measured period may be off the model's, relative (specs/trace.md §4)
PERIOD_TOLERANCE = Fraction(1, 100)


@dataclass(frozen=True)
class Where:
    """The model's text a finding points at."""

    project: Project

    def task_syntax(self, component: str, task: str) -> s.Task | None:
        for comp in self.project.components:
            if comp.name.text == component:
                return next((t for t in comp.tasks if t.name.text == task), None)
        return None

    def instance_span(self, model: SystemModel, name: str) -> Span:
        return next((i.span for i in model.instances if i.name == name), model.span)


def findings(model: SystemModel, analysis: AnalysisResult, recording: Recording, matching: Matching,
             measured: Measurements, project: Project, sink: DiagnosticSink,
             tolerance: Fraction = PERIOD_TOLERANCE, delays: Delays | None = None) -> None:
    where = Where(project)
    delays = delays or Delays((), ())
    _reading(recording, sink)
    _unmatched(model, recording, matching, where, sink)
    for m in measured.tasks:
        _execution(model, m, where, sink)
        _period(model, m, sink, tolerance)
    for c in measured.chains:
        chain = next(ch for ch in model.chains if ch.name == c.chain)
        bounds = analysis.chain(c.chain)
        for kind, got, bound in (("reaction_time", c.reaction_time, bounds.reaction_time.worst),
                                 ("data_age", c.data_age, bounds.data_age.worst)):
            if got is not None:
                _latency(model, chain, kind, got.max, bound, getattr(chain, kind), measured, delays, sink)
        if c.jitter is not None:
            _latency(model, chain, "jitter", c.jitter, bounds.jitter, chain.jitter, measured, delays, sink)


def _reading(recording: Recording, sink: DiagnosticSink) -> None:
    span = Span(recording.paths[0], 1, 1, 1, 1) if recording.paths else NO_SPAN
    for why in recording.partial:
        sink.emit("E806", f"the trace is read in part: {why}", span, "read in part", severity=Severity.WARNING,
                  help="the measurements are of what was read; record again for a whole trace")


def _unmatched(model: SystemModel, recording: Recording, matching: Matching, where: Where,
               sink: DiagnosticSink) -> None:
    for task_id, reason in matching.tasks_unmatched:
        task = model.task(task_id)
        sink.emit("E805", f"task `{task_id}` is not found in the trace: {reason}", task.span, "not measured",
                  help="name the node's instance as the node is named, activate the task as its callback is "
                       "(a timer, or a trigger on the port named after the topic); specs/trace.md §2")
    for key, reason in matching.callbacks_unmatched:
        c = recording.callbacks[key]
        instance = c.node and next((i.name for i in model.instances if language_name(c.node) == i.name), None)
        span = where.instance_span(model, instance) if instance else model.span
        sink.emit("E805", f"the trace's {c.describe()} is not paired with a task: {reason}", span, "not paired",
                  help="add the task it runs to the model, or leave it: it is not measured")


def _execution(model: SystemModel, m: TaskMeasure, where: Where, sink: DiagnosticSink) -> None:
    task = model.task(m.task)
    if m.execution is None or m.execution.max <= task.wcet:
        return
    syntax = where.task_syntax(task.component, task.name)
    span = syntax.wcet.span if syntax is not None and syntax.wcet is not None else task.definition_span
    above = ", ".join(f"job {k + 1}: {fmt_time(x)}" for k, x in m.overruns)
    cpu = m.cpu_jobs == m.execution.count
    ran, what = ("used up to", " of CPU time") if cpu else ("ran up to", "")
    sink.emit("E801", f"task `{m.task}` {ran} {fmt_time(m.execution.max)}{what} in the trace, above its wcet "
              f"{fmt_time(task.wcet)}: the bounds do not hold for this robot", span, "measured above this",
              secondary=[Label(task.span, "the instance's task")],
              notes=[f"measured over {m.execution.count} jobs{_measure_words(m)}: min {fmt_time(m.execution.min)}, "
                     f"p50 {fmt_time(m.execution.p50)}, p99 {fmt_time(m.execution.p99)}, max "
                     f"{fmt_time(m.execution.max)}",
                     f"{m.overrun_count} of {m.execution.count} jobs above the wcet: {above}"
                     + (" …" if m.overrun_count > len(m.overruns) else "")],
              help="find why the job overran, or write the measured time: `verify trace --calibrate`")


def _measure_words(m: TaskMeasure) -> str:
    """What the execution times are, when some are CPU times (job records' `cpu`)."""
    if not m.cpu_jobs or m.execution is None:
        return ""
    if m.cpu_jobs == m.execution.count:
        return " (the CPU time each job's thread spent on it)"
    return f" (the CPU time its thread spent for {m.cpu_jobs} of them, end − start for the others)"


def _period(model: SystemModel, m: TaskMeasure, sink: DiagnosticSink, tolerance: Fraction) -> None:
    task = model.task(m.task)
    if not isinstance(task.activation, Periodic):
        return
    period = task.activation.period
    span = task.activation.span if task.activation.span != NO_SPAN else task.span
    if m.configured_period is not None and m.configured_period != period:
        sink.emit("E802", f"the timer of `{m.task}` has the period {fmt_time(m.configured_period)} in the trace, "
                  f"not {fmt_time(period)}", span, "another period on the robot",
                  help="configure the robot's timer with the model's period, or write the robot's period here")
    elif m.mean_period is not None and abs(m.mean_period - period) > period * tolerance:
        sink.emit("E802", f"the timer of `{m.task}` ran with a mean period of {fmt_time(m.mean_period)} in the "
                  f"trace, more than {fmt_time(period * tolerance)} off its {fmt_time(period)}", span,
                  "another period on the robot", help="find what delays or hastens the timer (its clock, an "
                  "overloaded executor), or write the period measured")


def _latency(model: SystemModel, chain: ChainModel, kind: str, got: Fraction, bound: Fraction | None,
             spec: Fraction | None, measured: Measurements, delays: Delays, sink: DiagnosticSink) -> None:
    word = kind.replace("_", " ")
    if spec is not None and got > spec:
        sink.emit("E804", f"chain `{chain.name}`: the measured {word} {fmt_time(got)} is above its spec "
                  f"{fmt_time(spec)}", chain.spec_span(kind, chain.span), "violated on the robot",
                  notes=[_broken(model, chain, measured, delays)],
                  help="the robot misses this spec: change the system (`synth`), or the spec")
    elif bound is not None and got > bound:
        sink.emit("E803", f"chain `{chain.name}`: the measured {word} {fmt_time(got)} is above its bound "
                  f"{fmt_time(bound)} — an assumption of the bound broke: {_broken(model, chain, measured, delays)}",
                  chain.spec_span(kind, chain.span), "above the bound",
                  help="correct the assumption named (`verify trace --calibrate` writes measured execution times and "
                       "delays)")


def _broken(model: SystemModel, chain: ChainModel, measured: Measurements, delays: Delays) -> str:
    """The assumption of a chain's bound that the measurements contradict, in words."""
    said = []
    for task_id in chain.tasks:
        m = measured.task(task_id)
        task = model.task(task_id)
        if m is None or m.execution is None:
            continue
        if m.execution.max > task.wcet:
            ran = "used" if m.cpu_jobs == m.execution.count else "ran"
            what = " of CPU time" if ran == "used" else ""
            said.append(f"task `{task_id}` {ran} {fmt_time(m.execution.max)}{what}, above its wcet "
                        f"{fmt_time(task.wcet)}")
        elif m.cpu_jobs and m.elapsed is not None and m.elapsed.max > task.wcet:
            said.append(f"jobs of task `{task_id}` took up to {fmt_time(m.elapsed.max)} from start to finish, "
                        f"above its wcet {fmt_time(task.wcet)}, with at most {fmt_time(m.execution.max)} of CPU "
                        "time: other threads (if not the model's tasks: the middleware's, other processes') "
                        "took the CPU or the interpreter lock from them")
        if isinstance(task.activation, Periodic) and m.intervals is not None \
                and m.intervals.max > task.activation.period * (1 + PERIOD_TOLERANCE):
            said.append(f"the timer of `{task_id}` waited up to {fmt_time(m.intervals.max)} between jobs, its "
                        f"period is {fmt_time(task.activation.period)}")
    for h in chain.hops:
        c = delays.of(h.link.source, h.link.target)
        if c is not None and c.delays.max > c.delay_max:
            said.append(f"a message of `{c.connection}` took {fmt_time(c.delays.max)}, above its delay "
                        f"{fmt_time(c.delay_max)}")
    if said:
        return "; ".join(said)
    words = ", ".join(f"`{h.link.source} -> {h.link.target}` ≤ {fmt_time(h.link.delay_max)}" for h in chain.hops)
    return ("every task of the chain stayed within its wcet and period, so the connections took longer than their "
            f"delays ({words}) or the executor ran the callbacks in another order than the model assumed")


def distribution_words(d: Distribution | None) -> str:
    if d is None:
        return "none"
    return (f"min {fmt_time(d.min)}, p50 {fmt_time(d.p50)}, p99 {fmt_time(d.p99)}, max {fmt_time(d.max)} "
            f"({d.count})")
