"""The counterexample as an SVG Gantt chart (``prove --trace-svg``, specs/proof.md §8).

A chart reads at a glance: one row per task, grouped by core under the core's name (the cores in the
order the chain meets them, the tasks of a core by priority, highest first); the task names in a
column of their own, in a fixed-width font so that their width is known and never runs into the
plot; jobs as bars from start to completion (preemptions are not drawn; in a row crowded with more than
``CROWDED`` jobs, bars less than a pixel apart are drawn as one), releases as ticks; the chain's jobs
(or the late job) highlighted, the data flow between them as arrows; the violating interval shaded, a
dashed line where the spec (or deadline) ends; a time axis with round ticks (1, 2 or 5 times a power of
ten) and a legend. Times come from the run (``intsim.run_trace``, as the reference simulator); only
pixel positions are floats.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, cast
from xml.sax.saxutils import escape

from ..model.system import SystemModel
from .sim import JobRecord, Sample, Trace
from ..model.units import fmt_time
from .intsim import run_trace
from .scenario import ConcreteScenario, ResponseSample
from .trace import ChainStep, instant, job_chain
from .verdict import Verdict

#: a row with more jobs than this in the chart's interval draws bars less than a pixel apart as one
#: bar, and one release tick per pixel (an overloaded core can run thousands of jobs in the interval)
CROWDED = 200
#: the width of one character of the labels' fixed-width font at 12 px (0.6 em), and the longest label
CHAR_W = 7.2
MAX_LABEL = 48
PLOT_W, ROW_H, CORE_H, TOP = 900, 26, 22, 64
JOB, CHAIN_JOB, RED, GRID = "#aed6f1", "#e67e22", "#c0392b", "#e5e5e5"


def _num(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".")


def _rows(model: SystemModel, verdict: Verdict) -> list[str]:
    """The tasks of a chart: the chain's (or the late task's) and those sharing their cores."""
    return [t for _, tasks in _groups(model, verdict) for t in tasks]


def _groups(model: SystemModel, verdict: Verdict) -> list[tuple[str, list[str]]]:
    """(core, its tasks by priority, highest first; ties in system order) for every core of the chart,
    in the order the chain meets them (the late task's core for a deadline)."""
    if verdict.subject == "chain":
        chain = next(c for c in model.chains if c.name == verdict.name)
        cores = list(dict.fromkeys(model.task(t).core for t in chain.tasks))
    else:
        cex = verdict.counterexample
        assert cex is not None
        cores = [model.task(cast(ResponseSample, cex.sample).task).core]
    return [(core, [t.id for t in sorted(model.tasks_on(core), key=lambda t: -t.priority)]) for core in cores]


def chart_runs(model: SystemModel, verdicts: list[Verdict]) -> dict[ConcreteScenario, Trace]:
    """scenario -> its whole run with the jobs of every row of the charts of ``verdicts`` that
    show it (each scenario run once)."""
    rows: dict[ConcreteScenario, tuple[str, ...]] = {}
    for v in verdicts:
        assert v.counterexample is not None
        sc = v.counterexample.scenario
        rows[sc] = tuple(dict.fromkeys(rows.get(sc, ()) + tuple(_rows(model, v))))
    return {sc: run_trace(model, sc, tasks=list(tasks)) for sc, tasks in rows.items()}


def to_svg(model: SystemModel, verdict: Verdict, traces: dict[ConcreteScenario, Trace] | None = None) -> str:
    """The chart of one counterexample, as an SVG document."""
    return "\n".join(_chart(model, verdict, traces=traces)[2]) + "\n"


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


def nice_step(span: Fraction, ticks: int = 10) -> Fraction:
    """The least step of 1, 2 or 5 times a power of ten (seconds) that cuts ``span`` into at most
    ``ticks`` parts."""
    power = Fraction(1, 10**12)
    while True:
        for m in (1, 2, 5):
            if span / (m * power) <= ticks:
                return m * power
        power *= 10


def axis_ticks(t0: Fraction, t1: Fraction) -> list[Fraction]:
    """The multiples of ``nice_step`` between ``t0`` and ``t1`` (exact)."""
    step = nice_step(t1 - t0)
    first = -((-t0) // step) * step
    out = []
    t = first
    while t <= t1:
        out.append(t)
        t += step
    return out


@dataclass(frozen=True)
class _Frame:
    """Where things go: the time interval shown and the pixel geometry of one chart."""

    t0: Fraction
    t1: Fraction
    left: float
    rows: dict[str, float]  # task -> the top of its row

    def x(self, t: Fraction) -> float:
        return self.left + min(max(float((t - self.t0) / (self.t1 - self.t0)), 0.0), 1.0) * PLOT_W


def _chart(model: SystemModel, verdict: Verdict, marker: str = "arrow", position: bool = False,
           traces: dict[ConcreteScenario, Trace] | None = None) -> tuple[int, int, list[str]]:
    """(width, height, lines) of one counterexample's chart; its first line opens its ``svg`` element
    (without ``xmlns`` when it is to be nested: ``position``). ``traces``: ``chart_runs``."""
    cex = verdict.counterexample
    assert cex is not None
    groups = _groups(model, verdict)
    trace = (traces or chart_runs(model, [verdict]))[cex.scenario]
    steps: list[ChainStep] = []
    if verdict.subject == "chain":
        s = cast(Sample, cex.sample)
        lo, hi = s.begin, s.end
        steps = job_chain(model, trace, verdict.name, s)
        highlighted = {(st.job.task, st.job.index) for st in steps}
    else:
        r = cast(ResponseSample, cex.sample)
        lo, hi = r.release, r.finish if r.finish is not None else trace.horizon
        highlighted = {(r.task, r.index)}
    pad = max((hi - lo) / 10, Fraction(1, 10**6))
    t0, t1 = max(Fraction(0), lo - pad), hi + pad
    labels = {t: _label(model, t) for _, tasks in groups for t in tasks}
    left = 16 + CHAR_W * max(len(text) for text in labels.values()) + 16
    rows: dict[str, float] = {}
    y = TOP
    for _, tasks in groups:
        y += CORE_H
        for task in tasks:
            rows[task] = y
            y += ROW_H
    bottom = y
    f = _Frame(t0, t1, left, rows)
    width, height = int(left + PLOT_W + 40), int(bottom + 84)
    title = (f"{verdict.label}: {fmt_time(cex.latency)} > {fmt_time(verdict.spec)} "
             f"(counterexample by {verdict.method})")
    xmlns = "" if position else 'xmlns="http://www.w3.org/2000/svg" '
    out = [f'<svg {xmlns}width="{width}" height="{height}" viewBox="0 0 {width} {height}" '
           'font-family="sans-serif" font-size="12">',
           f"<title>{escape(title)}</title>",
           f'<defs><marker id="{marker}" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" markerHeight="7" '
           f'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="{RED}"/></marker></defs>',
           '<rect x="0" y="0" width="100%" height="100%" fill="white"/>',
           f'<text x="10" y="20" font-size="14" font-weight="bold">{escape(title)}</text>',
           f'<text x="10" y="40" fill="#555">{escape(cex.scenario.summary(model))}</text>']
    out += _axis(f, TOP, bottom)
    out += _cores(groups, f, left, width)
    out.append(f'<rect class="violation" x="{_num(f.x(lo))}" y="{TOP}" width="{_num(f.x(hi) - f.x(lo))}" '
               f'height="{_num(bottom - TOP)}" fill="#f5b7b1" fill-opacity="0.35" stroke="{RED}" '
               'stroke-dasharray="4 3"/>')
    out += _spec_line(verdict, f, lo, TOP, bottom)
    for task, label in labels.items():
        yy = rows[task]
        shown = label if len(label) <= MAX_LABEL else label[:MAX_LABEL - 1] + "…"
        out.append(f'<text class="task" x="16" y="{_num(yy + 17)}" font-family="monospace">'
                   f'{escape(shown)}<title>{escape(label)}</title></text>')
        out.append(f'<line x1="{_num(left)}" y1="{_num(yy + ROW_H)}" x2="{_num(left + PLOT_W)}" '
                   f'y2="{_num(yy + ROW_H)}" stroke="{GRID}"/>')
        jobs = [j for j in trace.jobs[task] if t0 <= j.release <= t1 or (
            j.start is not None and j.start <= t1 and (j.finish if j.finish is not None else trace.horizon) >= t0)]
        out += _row(jobs, f.x, yy, ROW_H, t0, t1, highlighted, trace.horizon)
    out += _flows(steps, f, marker)
    out.append(f'<text x="{_num((f.x(lo) + f.x(hi)) / 2)}" y="{_num(bottom + 34)}" text-anchor="middle" '
               f'fill="{RED}">{escape(_measured(verdict, lo, hi))}</text>')
    out += _legend(verdict, left, bottom + 60, marker)
    out.append("</svg>")
    return width, height, out


def _label(model: SystemModel, task: str) -> str:
    return f"{task}  prio {model.task(task).priority}"


def _cores(groups: list[tuple[str, list[str]]], f: _Frame, left: float, width: int) -> list[str]:
    """The name of each core above its rows, and a line that separates it from the core above."""
    out = []
    for core, tasks in groups:
        y = f.rows[tasks[0]] - CORE_H
        out.append(f'<line class="core" x1="10" y1="{_num(y + 2)}" x2="{_num(left + PLOT_W)}" y2="{_num(y + 2)}" '
                   'stroke="#888"/>')
        out.append(f'<text class="core" x="10" y="{_num(y + 16)}" font-weight="bold">core {escape(core)}</text>')
    return out


def _axis(f: _Frame, top: float, bottom: float) -> list[str]:
    """Round ticks: a light vertical line through the rows and the time below."""
    out = []
    for t in axis_ticks(f.t0, f.t1):
        at = _num(f.x(t))
        out.append(f'<line class="tick" x1="{at}" y1="{_num(top)}" x2="{at}" y2="{_num(bottom + 4)}" stroke="{GRID}"/>')
        out.append(f'<text class="tick" x="{at}" y="{_num(bottom + 18)}" text-anchor="middle" fill="#555">'
                   f'{escape(fmt_time(t))}</text>')
    return out


def _spec_line(verdict: Verdict, f: _Frame, lo: Fraction, top: float, bottom: float) -> list[str]:
    """A dashed line where the latency (or response) would have to end to meet the spec (or deadline)."""
    at = lo + verdict.spec
    if not f.t0 <= at <= f.t1 or verdict.kind == "jitter":
        return []
    word = "deadline" if verdict.kind == "deadline" else "spec"
    x = _num(f.x(at))
    return [f'<line class="spec" x1="{x}" y1="{_num(top - 4)}" x2="{x}" y2="{_num(bottom)}" stroke="#2c3e50" '
            'stroke-width="1.5" stroke-dasharray="6 3"/>',
            f'<text class="spec" x="{x}" y="{_num(top - 8)}" text-anchor="middle" fill="#2c3e50">'
            f'{word} {escape(fmt_time(verdict.spec))}</text>']


def _measured(verdict: Verdict, lo: Fraction, hi: Fraction) -> str:
    cex = verdict.counterexample
    assert cex is not None
    if cex.best_sample is None:
        return f"{fmt_time(hi - lo)} (spec {fmt_time(verdict.spec)})"
    # jitter: this run holds the largest sample; the smallest comes from a second run (not drawn)
    return (f"{fmt_time(hi - lo)} here; jitter {fmt_time(cex.latency)} = {fmt_time(cast(Sample, cex.sample).value)} − "
            f"{fmt_time(cast(Sample, cex.best_sample).value)} of a second run (spec {fmt_time(verdict.spec)})")


def _flows(steps: list[ChainStep], f: _Frame, marker: str) -> list[str]:
    out = []
    for a, b in zip(steps, steps[1:]):
        m = a.message
        if m is None or b.job.start is None:
            continue
        out.append(f'<line class="flow" x1="{_num(f.x(m.written))}" y1="{_num(f.rows[a.job.task] + ROW_H / 2)}" '
                   f'x2="{_num(f.x(b.job.start))}" y2="{_num(f.rows[b.job.task] + ROW_H / 2)}" stroke="{RED}" '
                   f'stroke-width="1.5" marker-end="url(#{marker})"><title>{escape(m.source)} -> {escape(m.target)}: '
                   f'written {escape(instant(m.written))}, arrives {escape(instant(m.arrival))}</title></line>')
    return out


def _legend(verdict: Verdict, left: float, y: float, marker: str) -> list[str]:
    """What each mark means, in one line below the axis."""
    late = "job of the chain" if verdict.subject == "chain" else "the late job"
    items: list[tuple[str, str]] = [
        (f'<rect x="0" y="-9" width="22" height="10" fill="{JOB}" stroke="#2c3e50"/>', "job: start to completion"),
        (f'<rect x="0" y="-9" width="22" height="10" fill="{CHAIN_JOB}" stroke="#2c3e50"/>', late),
        ('<line x1="11" y1="-11" x2="11" y2="3" stroke="#333"/>', "release"),
    ]
    if verdict.subject == "chain":
        items.append((f'<line x1="0" y1="-4" x2="22" y2="-4" stroke="{RED}" stroke-width="1.5" '
                      f'marker-end="url(#{marker})"/>', "data flow"))
    if verdict.kind != "jitter":  # (a jitter spec is no point in time: no line)
        items.append(('<line x1="11" y1="-11" x2="11" y2="3" stroke="#2c3e50" stroke-width="1.5" '
                      'stroke-dasharray="6 3"/>', "deadline" if verdict.kind == "deadline" else "spec"))
    items += [(f'<rect x="0" y="-9" width="22" height="10" fill="#f5b7b1" fill-opacity="0.35" stroke="{RED}" '
               'stroke-dasharray="4 3"/>', "violating interval")]
    out = [f'<g class="legend" transform="translate({_num(left)} {_num(y)})">']
    x = 0.0
    for mark, text in items:
        out.append(f'<g transform="translate({_num(x)} 0)">{mark}<text x="28" y="0">{escape(text)}</text></g>')
        x += 28 + 6.8 * len(text) + 22
    out.append("</g>")
    return out


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
                     f"{escape(instant(first.start))} to {escape(instant(last.finish))}")
        else:
            title = (f"{escape(first.task)}#{first.index}: released {escape(instant(first.release))}, "
                     f"starts {escape(instant(first.start))}, completes {escape(instant(first.finish))}")
        out[place] = (f'<rect class="job{" chain" if on else ""}" x="{_num(x0)}" y="{_num(yy + 5)}" '
                      f'width="{_num(max(x1 - x0, 1.0))}" height="{row_h - 10}" '
                      f'fill="{CHAIN_JOB if on else JOB}" stroke="#2c3e50"><title>{title}</title></rect>')
        pending.clear()

    for j in jobs:
        if t0 <= j.release <= t1:
            at = _num(x(j.release))
            if not crowded or at not in ticked:
                ticked.add(at)
                out.append(f'<line class="release" x1="{at}" y1="{_num(yy + 2)}" x2="{at}" '
                           f'y2="{_num(yy + row_h - 2)}" stroke="#333"/>')
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
