"""Counterexample timelines: text and JSON (specs/proof.md §8; the SVG Gantt chart: ``verify.prove.gantt``).

Every view starts from a ``Counterexample`` and runs its scenario (``intsim.run_trace``, the same
trace as the reference simulator ``verify.prove.sim`` gives — tests/test_intsim.py — at a fraction of the
cost on large systems); nothing is drawn that the run did not produce. The job chain is found by walking back from
the last task's job through the values it read (provenance, specs/timing.md §4).
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, TypeAlias, cast

from ..model.system import SystemModel, TaskModel
from .sim import JobRecord, Message, Sample, Trace
from ..timing.report import exact
from ..model.units import fmt_time
from .intsim import run_trace
from .scenario import ConcreteScenario, ResponseSample
from .verdict import Verdict

# ``Counterexample.sample`` and ``best_sample`` are typed ``object``: they are the extreme samples
# ``Counterexample.of`` takes from ``scenario.Extremes``, a ``verify.prove.sim.Sample`` for a chain verdict
# and a ``scenario.ResponseSample`` for a task's deadline (the casts below say which one a view has).
AnySample: TypeAlias = "Sample | ResponseSample"


@dataclass(frozen=True)
class ChainStep:
    """One job of the job chain and the message it wrote along the chain (None for the last)."""

    job: JobRecord
    message: Message | None


def job_chain(model: SystemModel, trace: Trace, chain_name: str, sample: Sample) -> list[ChainStep]:
    """The jobs τ₁#stamp → … → τₙ#last through which the sample's value flowed."""
    chain = next(c for c in model.chains if c.name == chain_name)
    job = trace.job(chain.tasks[-1], sample.last)
    steps = [ChainStep(job, None)]
    for pos in range(len(chain.tasks) - 1, 0, -1):
        msg = job.read(chain.hops[pos - 1].link.target)
        if msg is None:
            break
        job = trace.job(msg.writer, msg.job)
        steps.append(ChainStep(job, msg))
    steps.reverse()  # each step carries the message its job wrote and the next job read
    return steps


class Runs:
    """The runs the text and JSON views of several counterexamples show, each scenario run once: with
    the jobs of the chains' tasks for a chain verdict, up to the last sample's end among them (every
    job and message of a job chain is there by then, and a longer run holds the same records for
    them); with the jobs of the task's core for a task's response, to the end of the run."""

    def __init__(self, model: SystemModel, verdicts: Iterable[Verdict] = ()):
        self.model = model
        # scenario -> (last sample end, tasks)
        self.wanted: dict[ConcreteScenario, tuple[Fraction, tuple[str, ...]]] = {}
        for v in verdicts:
            if v.counterexample is not None:
                self._want(v)
        self.traces: dict[ConcreteScenario, Trace] = {}

    def _want(self, v: Verdict) -> None:
        cex, model = v.counterexample, self.model
        assert cex is not None
        shown: Sequence[str]
        if v.subject == "chain":
            end = cast(Sample, cex.sample).end
            shown = next(c for c in model.chains if c.name == v.name).tasks
        else:  # the whole run: a job running across the response's end shows when it completes
            end = cex.scenario.horizon
            shown = [t.id for t in model.tasks_on(model.task(cex.target.name).core)]
        last, tasks = self.wanted.get(cex.scenario, (end, ()))
        self.wanted[cex.scenario] = (max(last, end), tuple(dict.fromkeys(tasks + tuple(shown))))

    def of(self, verdict: Verdict) -> Trace:
        cex = verdict.counterexample
        assert cex is not None
        if cex.scenario not in self.wanted:
            self._want(verdict)
        if cex.scenario not in self.traces:
            end, tasks = self.wanted[cex.scenario]
            cut = cex.scenario.with_horizon(min(cex.scenario.horizon, end + Fraction(1, 10**12)))
            self.traces[cex.scenario] = run_trace(self.model, cut, tasks=tasks)
        return self.traces[cex.scenario]


def instant(x: Fraction | None) -> str:
    """A time of a run as text; "-" when it has not happened."""
    return "-" if x is None else fmt_time(x)


# ------------------------------------------------------------------ text


def to_text(model: SystemModel, verdict: Verdict, runs: Runs | None = None) -> str:
    cex = verdict.counterexample
    assert cex is not None
    trace = (runs or Runs(model)).of(verdict)
    lines = [f"counterexample: {verdict.label} {fmt_time(cex.latency)} > spec {fmt_time(verdict.spec)} "
             f"(by {verdict.method})",
             f"  scenario: {cex.scenario.summary(model)}; the run lasts {fmt_time(cex.scenario.horizon)}"]
    if verdict.subject == "task":
        r = cast(ResponseSample, cex.sample)
        lines.append(f"  job {r.task}#{r.index}: released {instant(r.release)}, completes {instant(r.finish)}: "
                     f"response {fmt_time(r.value)}")
        job = trace.job(r.task, r.index)
        lines.append(f"  it starts at {instant(job.start)}; jobs of its core running in between:")
        core = model.task(r.task).core
        end = r.finish if r.finish is not None else trace.horizon
        for t in model.tasks_on(core):
            between = [j for j in trace.jobs[t.id] if j.start is not None and j.start < end
                       and (j.finish is None or j.finish > r.release) and (t.id, j.index) != (r.task, r.index)]
            lines += _listed(t, between)
        return "\n".join(lines)
    s = cast(Sample, cex.sample)
    chain = next(c for c in model.chains if c.name == verdict.name)
    first = chain.tasks[0]
    if verdict.kind == "reaction_time":
        nxt = s.origin + 1
        sampled = trace.job(first, nxt).start if nxt < len(trace.jobs[first]) else None
        lines.append(f"  stimulus just after the read of {first}#{s.origin} at {fmt_time(s.begin)}; it is first "
                     f"read by {first}#{nxt} at {instant(sampled)}")
    else:
        lines.append(f"  the value read by {first}#{s.stamp} at {fmt_time(s.begin)}"
                     + (" (measured from that job's previous read)" if verdict.variant == "non-reduced" else ""))
    lines.append("  job chain (each job reads at its start and writes at its completion):")
    steps = job_chain(model, trace, verdict.name, s)
    width = max(len(f"{st.job.task}#{st.job.index}") for st in steps)
    for step in steps:
        j = step.job
        lines.append(f"    {f'{j.task}#{j.index}'.ljust(width)}  released {instant(j.release):>10}  reads at "
                     f"{instant(j.start):>10}  completes {instant(j.finish):>10}")
        if step.message is not None:
            m = step.message
            lines.append(f"      -> {m.source} -> {m.target}: written {instant(m.written)}, "
                         f"arrives {instant(m.arrival)}")
    lines.append(f"  latency: {fmt_time(s.end)} − {fmt_time(s.begin)} = {fmt_time(s.value)}")
    if verdict.kind == "jitter":
        b = cast(Sample, cex.best_sample)
        assert cex.best_scenario is not None
        lines.append(f"  a second run ({cex.best_scenario.summary(model)}) has a data age of {fmt_time(b.value)}: "
                     f"jitter {fmt_time(s.value)} − {fmt_time(b.value)} = {fmt_time(cex.latency)}")
    return "\n".join(lines)


#: a task with more jobs than this in the interval of a response shows its first and last ones
LISTED_JOBS = 6


def _listed(task: TaskModel, jobs: list[JobRecord]) -> list[str]:
    """The lines of ``task``'s jobs in a response's interval; past ``LISTED_JOBS`` of them, the first
    and last few and a line that counts the rest (an overloaded core can hold thousands)."""
    def line(j: JobRecord) -> str:
        return (f"    {task.id}#{j.index}  [priority {task.priority}]  released {instant(j.release)}, "
                f"starts {instant(j.start)}, completes {instant(j.finish)}")

    if len(jobs) <= LISTED_JOBS:
        return [line(j) for j in jobs]
    half = LISTED_JOBS // 2
    hidden = jobs[half:-half]
    return ([line(j) for j in jobs[:half]]
            + [f"    … {len(hidden)} more jobs of {task.id} (#{hidden[0].index} to #{hidden[-1].index}), released "
               f"{instant(hidden[0].release)} to {instant(hidden[-1].release)}"]
            + [line(j) for j in jobs[-half:]])


# ------------------------------------------------------------------ JSON


def _job_json(j: JobRecord) -> dict[str, Any]:
    return {"task": j.task, "index": j.index, "release": exact(j.release), "start": exact(j.start),
            "finish": exact(j.finish), "execution_time": exact(j.exec_time)}


def _sample_json(s: AnySample) -> dict[str, Any]:
    if isinstance(s, Sample):  # (the chain samples; a ``ResponseSample`` has no ``origin``)
        return {"value": exact(s.value), "begin": exact(s.begin), "end": exact(s.end), "origin_job": s.origin,
                "stamp_job": s.stamp, "last_job": s.last}
    return {"value": exact(s.value), "task": s.task, "job": s.index, "release": exact(s.release),
            "finish": exact(s.finish)}


def to_json(model: SystemModel, verdict: Verdict, runs: Runs | None = None) -> dict[str, Any]:
    cex = verdict.counterexample
    assert cex is not None
    doc: dict[str, Any] = {"target": {"kind": cex.target.kind, "name": cex.target.name},
                           "latency": exact(cex.latency), "spec": exact(verdict.spec),
                           "scenario": cex.scenario.to_json(), "sample": _sample_json(cast(AnySample, cex.sample))}
    trace = (runs or Runs(model)).of(verdict)
    if verdict.subject == "chain":
        doc["job_chain"] = [dict(_job_json(st.job), message=None if st.message is None else {
            "source": st.message.source, "target": st.message.target, "index": st.message.index,
            "written": exact(st.message.written), "arrival": exact(st.message.arrival)})
            for st in job_chain(model, trace, verdict.name, cast(Sample, cex.sample))]
    else:
        r = cast(ResponseSample, cex.sample)
        doc["job"] = _job_json(trace.job(r.task, r.index))
    if cex.best_scenario is not None:
        doc["best_scenario"] = cex.best_scenario.to_json()
        doc["best_sample"] = _sample_json(cast(AnySample, cex.best_sample))
    return doc
