"""Counterexample timelines: text, JSON and an SVG Gantt chart (specs/proof.md §8).

Every view starts from a ``Counterexample`` and runs its scenario (``intsim.run_trace``, the same
trace as the reference simulator ``verify.sim`` gives — tests/test_intsim.py — at a fraction of the
cost on large systems); nothing is drawn that the run did not produce. The job chain is found by walking back from
the last task's job through the values it read (provenance, specs/timing.md §4).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, TypeAlias, cast
from xml.sax.saxutils import escape

from ..model import SystemModel, TaskModel
from ..sim import JobRecord, Message, Sample, Trace
from ..timing.report import exact
from ..units import fmt_time
from .intsim import run_trace
from .scenario import ConcreteScenario, ResponseSample
from .verdict import Verdict

# ``Counterexample.sample`` and ``best_sample`` are typed ``object``: they are the extreme samples
# ``Counterexample.of`` takes from ``scenario.Extremes``, a ``verify.sim.Sample`` for a chain verdict
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


def _t(x: Fraction | None) -> str:
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
        lines.append(f"  job {r.task}#{r.index}: released {_t(r.release)}, completes {_t(r.finish)}: "
                     f"response {fmt_time(r.value)}")
        job = trace.job(r.task, r.index)
        lines.append(f"  it starts at {_t(job.start)}; jobs of its core running in between:")
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
                     f"read by {first}#{nxt} at {_t(sampled)}")
    else:
        lines.append(f"  the value read by {first}#{s.stamp} at {fmt_time(s.begin)}"
                     + (" (measured from that job's previous read)" if verdict.variant == "non-reduced" else ""))
    lines.append("  job chain (each job reads at its start and writes at its completion):")
    steps = job_chain(model, trace, verdict.name, s)
    width = max(len(f"{st.job.task}#{st.job.index}") for st in steps)
    for step in steps:
        j = step.job
        lines.append(f"    {f'{j.task}#{j.index}'.ljust(width)}  released {_t(j.release):>10}  reads at "
                     f"{_t(j.start):>10}  completes {_t(j.finish):>10}")
        if step.message is not None:
            m = step.message
            lines.append(f"      -> {m.source} -> {m.target}: written {_t(m.written)}, arrives {_t(m.arrival)}")
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
        return (f"    {task.id}#{j.index}  [priority {task.priority}]  released {_t(j.release)}, "
                f"starts {_t(j.start)}, completes {_t(j.finish)}")

    if len(jobs) <= LISTED_JOBS:
        return [line(j) for j in jobs]
    half = LISTED_JOBS // 2
    hidden = jobs[half:-half]
    return ([line(j) for j in jobs[:half]]
            + [f"    … {len(hidden)} more jobs of {task.id} (#{hidden[0].index} to #{hidden[-1].index}), released "
               f"{_t(hidden[0].release)} to {_t(hidden[-1].release)}"]
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


# ------------------------------------------------------------------ SVG


def _num(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


def to_svg(model: SystemModel, verdict: Verdict, traces: dict[ConcreteScenario, Trace] | None = None) -> str:
    """A Gantt chart of the counterexample: one row per task (the chain's tasks and the tasks sharing
    their cores), jobs as bars from start to completion (preemptions are not drawn; in a row crowded
    with more than ``CROWDED`` jobs, bars less than a pixel apart are drawn as one), releases as
    ticks, the chain's jobs highlighted with data-flow arrows, the violating interval shaded."""
    return "\n".join(_chart(model, verdict, traces=traces)[2]) + "\n"


def _rows(model: SystemModel, verdict: Verdict) -> list[str]:
    """The tasks of a chart, top to bottom."""
    if verdict.subject == "chain":
        chain = next(c for c in model.chains if c.name == verdict.name)
        cores = {model.task(t).core for t in chain.tasks}
        return list(dict.fromkeys(list(chain.tasks) + [t.id for c in sorted(cores) for t in sorted(
            model.tasks_on(c), key=lambda t: -t.priority)]))
    cex = verdict.counterexample
    assert cex is not None
    core = model.task(cast(ResponseSample, cex.sample).task).core
    return [t.id for t in sorted(model.tasks_on(core), key=lambda t: -t.priority)]


def chart_runs(model: SystemModel, verdicts: list[Verdict]) -> dict[ConcreteScenario, Trace]:
    """scenario -> its whole run with the jobs of every row of the charts of ``verdicts`` that
    show it (each scenario run once)."""
    rows: dict[ConcreteScenario, tuple[str, ...]] = {}
    for v in verdicts:
        assert v.counterexample is not None
        sc = v.counterexample.scenario
        rows[sc] = tuple(dict.fromkeys(rows.get(sc, ()) + tuple(_rows(model, v))))
    return {sc: run_trace(model, sc, tasks=list(tasks)) for sc, tasks in rows.items()}


def to_svg_all(model: SystemModel, verdicts: list[Verdict]) -> str:
    """One SVG document with the chart of every counterexample of ``verdicts``, one below the other
    (each a nested ``svg``; for a single one, ``to_svg``)."""
    traces = chart_runs(model, verdicts)
    if len(verdicts) == 1:
        return to_svg(model, verdicts[0], traces)
    charts = [_chart(model, v, f"arrow{i}", position=True, traces=traces) for i, v in enumerate(verdicts, 1)]
    width = max(w for w, _, _ in charts)
    out, y = [], 0
    for _w, h, lines in charts:
        out.append(lines[0].replace("<svg ", f'<svg x="0" y="{y}" ', 1))
        out.extend(lines[1:])
        y += h
    head = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{y}" viewBox="0 0 {width} {y}" '
            'font-family="sans-serif" font-size="12">')
    title = f"<title>{len(verdicts)} counterexamples of {escape(model.name)}</title>"
    return "\n".join([head, title, '<rect x="0" y="0" width="100%" height="100%" fill="white"/>', *out,
                      "</svg>"]) + "\n"


def _chart(model: SystemModel, verdict: Verdict, marker: str = "arrow", position: bool = False,
           traces: dict[ConcreteScenario, Trace] | None = None) -> tuple[int, int, list[str]]:
    """(width, height, lines) of one counterexample's chart; its first line opens its ``svg`` element
    (without ``xmlns`` when it is to be nested: ``position``). ``traces``: ``chart_runs``."""
    cex = verdict.counterexample
    assert cex is not None
    rows = _rows(model, verdict)
    trace = (traces or chart_runs(model, [verdict]))[cex.scenario]
    if verdict.subject == "chain":
        s = cast(Sample, cex.sample)
        steps = job_chain(model, trace, verdict.name, s)
        lo, hi = s.begin, s.end
        highlighted = {(st.job.task, st.job.index) for st in steps}
    else:
        r = cast(ResponseSample, cex.sample)
        steps = []
        lo = r.release
        hi = r.finish if r.finish is not None else trace.horizon
        highlighted = {(r.task, r.index)}
    pad = max((hi - lo) / 10, Fraction(1, 10**6))
    t0, t1 = max(Fraction(0), lo - pad), hi + pad
    left, width, row_h, top = 230, 900, 30, 60
    height = top + row_h * len(rows) + 50

    lo_f, span_f = float(t0), float(t1 - t0)  # (pixels are drawn in floats; the times stay exact)

    def x(t: Fraction) -> float:
        return left + min(max((float(t) - lo_f) / span_f, 0.0), 1.0) * width

    def y(task: str) -> float:
        return top + row_h * rows.index(task)

    title = (f"{verdict.label}: {fmt_time(cex.latency)} > {fmt_time(verdict.spec)} "
             f"(counterexample by {verdict.method})")
    xmlns = "" if position else 'xmlns="http://www.w3.org/2000/svg" '
    out = [f'<svg {xmlns}width="{left + width + 40}" height="{height}" '
           f'viewBox="0 0 {left + width + 40} {height}" font-family="sans-serif" font-size="12">',
           f"<title>{escape(title)}</title>",
           f'<defs><marker id="{marker}" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" markerHeight="7" '
           'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="#c0392b"/></marker></defs>',
           '<rect x="0" y="0" width="100%" height="100%" fill="white"/>',
           f'<text x="10" y="20" font-size="14" font-weight="bold">{escape(title)}</text>',
           f'<text x="10" y="40" fill="#555">{escape(cex.scenario.summary(model))}</text>']
    out.append(f'<rect class="violation" x="{_num(x(lo))}" y="{top - 8}" width="{_num(x(hi) - x(lo))}" '
               f'height="{row_h * len(rows) + 8}" fill="#f5b7b1" fill-opacity="0.35" stroke="#c0392b" '
               'stroke-dasharray="4 3"/>')
    if cex.best_sample is None:
        label = f"{fmt_time(hi - lo)} (spec {fmt_time(verdict.spec)})"
    else:  # jitter: this run holds the largest sample; the smallest comes from a second run (not drawn)
        label = (f"{fmt_time(hi - lo)} here; jitter {fmt_time(cex.latency)} = "
                 f"{fmt_time(cast(Sample, cex.sample).value)} − "
                 f"{fmt_time(cast(Sample, cex.best_sample).value)} of a second run (spec {fmt_time(verdict.spec)})")
    out.append(f'<text x="{_num((x(lo) + x(hi)) / 2)}" y="{top + row_h * len(rows) + 16}" text-anchor="middle" '
               f'fill="#c0392b">{escape(label)}</text>')
    for task in rows:
        yy = y(task)
        out.append(f'<text x="10" y="{_num(yy + 19)}">{escape(task)} [{escape(model.task(task).core)}, '
                   f'priority {model.task(task).priority}]</text>')
        out.append(f'<line x1="{left}" y1="{_num(yy + row_h - 2)}" x2="{left + width}" y2="{_num(yy + row_h - 2)}" '
                   'stroke="#ddd"/>')
        shown = [j for j in trace.jobs[task] if t0 <= j.release <= t1 or (
            j.start is not None and j.start <= t1 and (j.finish if j.finish is not None else trace.horizon) >= t0)]
        out += _row(shown, x, yy, row_h, t0, t1, highlighted, trace.horizon)
    for a, b in zip(steps, steps[1:]):
        m = a.message
        if m is None or b.job.start is None:
            continue
        out.append(f'<line class="flow" x1="{_num(x(m.written))}" y1="{_num(y(a.job.task) + row_h / 2)}" '
                   f'x2="{_num(x(b.job.start))}" y2="{_num(y(b.job.task) + row_h / 2)}" stroke="#c0392b" '
                   f'stroke-width="1.5" marker-end="url(#{marker})"><title>{escape(m.source)} -> {escape(m.target)}: '
                   f'written {escape(_t(m.written))}, arrives {escape(_t(m.arrival))}</title></line>')
    for frac in range(0, 5):
        t = t0 + (t1 - t0) * frac / 4
        out.append(f'<text x="{_num(x(t))}" y="{height - 12}" text-anchor="middle" fill="#555">'
                   f'{escape(fmt_time(t))}</text>')
    out.append("</svg>")
    return left + width + 40, height, out


#: a row with more jobs than this in the chart's interval draws bars less than a pixel apart as one
#: bar, and one release tick per pixel (an overloaded core can run thousands of jobs in the interval)
CROWDED = 200


def _row(jobs: list[JobRecord], x: Callable[[Fraction], float], yy: float, row_h: int, t0: Fraction,
         t1: Fraction, highlighted: set[tuple[str, int]], horizon: Fraction) -> list[str]:
    """The release ticks and job bars of one row of a chart, in job order."""
    out: list[str] = []
    crowded = len(jobs) > CROWDED
    ticked: set[str] = set()
    pending: list[Any] = []  # the bar not drawn yet: [x from, x to, first job, last job, jobs merged (0: chain),
    #                    its place in ``out``] (floats, JobRecords and ints: hence Any)

    def flush() -> None:
        if not pending:
            return
        x0, x1, first, last, count, place = pending
        on = count == 0
        if count > 1:
            title = (f"{escape(first.task)}#{first.index} to #{last.index} ({count} jobs): from "
                     f"{escape(_t(first.start))} to {escape(_t(last.finish))}")
        else:
            title = (f"{escape(first.task)}#{first.index}: released {escape(_t(first.release))}, "
                     f"starts {escape(_t(first.start))}, completes {escape(_t(first.finish))}")
        out[place] = (f'<rect class="job{" chain" if on else ""}" x="{_num(x0)}" y="{_num(yy + 6)}" '
                      f'width="{_num(max(x1 - x0, 1.0))}" height="{row_h - 14}" '
                      f'fill="{"#e67e22" if on else "#aed6f1"}" stroke="#2c3e50"><title>{title}</title></rect>')
        pending.clear()

    for j in jobs:
        if t0 <= j.release <= t1:
            at = _num(x(j.release))
            if not crowded or at not in ticked:
                ticked.add(at)
                out.append(f'<line class="release" x1="{at}" y1="{_num(yy + 2)}" x2="{at}" '
                           f'y2="{_num(yy + row_h - 4)}" stroke="#333"/>')
        if j.start is None:
            continue
        end = j.finish if j.finish is not None else horizon
        if end < t0 or j.start > t1:
            continue
        x0, x1 = x(j.start), x(end)
        on = (j.task, j.index) in highlighted
        if crowded and not on and pending and pending[4] and x0 <= pending[1] + 1:
            pending[1], pending[3] = max(pending[1], x1), j
            pending[4] += 1
            continue
        flush()
        pending.extend([x0, x1, j, j, 0 if on else 1, len(out)])
        out.append("")  # (its place: the bar comes before the ticks of the jobs merged into it)
        if not crowded:
            flush()
    flush()
    return out
