"""A trace's measurements as text and as JSON (schema ``verify.trace/1``): per task the measured
execution time against [bcet, wcet] (the CPU time where job records give it, with start to finish and
release to finish beside it) and the activation against the period; per chain the measured latencies
against bound and spec; what was not paired."""
from __future__ import annotations

from fractions import Fraction
from typing import Any

from ..model.units import fmt_time
from .metrics import Distribution
from .run import TraceResult


def _q(x: Fraction | None) -> str | None:
    """An exact time for JSON: seconds as "N" or "N/D"."""
    return None if x is None else str(x)


def _dist(d: Distribution | None) -> dict[str, Any] | None:
    if d is None:
        return None
    return {"count": d.count, "min_s": _q(d.min), "p50_s": _q(d.p50), "p99_s": _q(d.p99), "max_s": _q(d.max)}


def _words(d: Distribution | None) -> str:
    if d is None:
        return "no jobs"
    return f"{fmt_time(d.min)} / {fmt_time(d.p50)} / {fmt_time(d.p99)} / {fmt_time(d.max)}"


def to_text(result: TraceResult) -> str:
    rec = result.recording
    lines = [f"trace of system {result.system}: {rec.events:,} events ({rec.source}) from " + ", ".join(rec.paths)]
    if rec.partial:
        lines.append("PARTIAL: " + "; ".join(rec.partial))
    lines += ["", "tasks (execution time min / p50 / p99 / max against [bcet, wcet]; activation):"]
    model = result.analysis
    for m in result.measured.tasks:
        t = model.task(m.task)
        if m.execution is None:  # (a bag's topic: when its messages were written, not how long jobs ran)
            lines.append(f"  {m.task}: {m.jobs} messages on {m.callback}")
            if m.mean_period is not None and m.intervals is not None:
                lines.append(f"    activation: mean period {fmt_time(m.mean_period)}, gaps {fmt_time(m.intervals.min)}"
                             f" .. {fmt_time(m.intervals.max)}")
            continue
        ok = "over wcet" if m.execution.max > t.wcet else "ok"
        lines.append(f"  {m.task}: {m.jobs} jobs, {_words(m.execution)} in [{fmt_time(t.bcet)}, {fmt_time(t.wcet)}]"
                     f" {ok}")
        lines.append(f"    {m.callback}")
        if m.cpu_jobs:
            lines.append(f"    execution time = the CPU time of the job's thread ({m.cpu_jobs} of {m.jobs} jobs); "
                         f"start to finish {_words(m.elapsed)}"
                         + (f"; response (release to finish) {_words(m.response)}" if m.response else ""))
        if m.mean_period is not None:
            gaps = m.intervals
            lines.append(f"    activation: mean period {fmt_time(m.mean_period)}"
                         + (f", gaps {fmt_time(gaps.min)} .. {fmt_time(gaps.max)}" if gaps else "")
                         + (f" (timer period {fmt_time(m.configured_period)})" if m.configured_period else ""))
    if result.measured.chains:
        lines += ["", "chains (measured max against bound and spec):"]
    for c in result.measured.chains:
        if c.missing:
            lines.append(f"  {c.chain}: not measured ({c.missing})")
            continue
        b = model.chain(c.chain)
        spec = {s.kind: s.spec for s in b.specs}
        for kind, d, bound in (("reaction time", c.reaction_time, b.reaction_time.worst),
                               ("data age", c.data_age, b.data_age.worst)):
            s = spec.get(kind.replace(" ", "_"))
            lines.append(f"  {c.chain} {kind}: {_words(d)}; bound {fmt_time(bound)}"
                         + (f", spec {fmt_time(s)}" if s is not None else ""))
        if c.jitter is not None:
            s = spec.get("jitter")
            lines.append(f"  {c.chain} jitter: {fmt_time(c.jitter)}; bound {fmt_time(b.jitter)}"
                         + (f", spec {fmt_time(s)}" if s is not None else ""))
    lines += _connection_lines(result)
    unpaired = len(result.matching.tasks_unmatched) + len(result.matching.callbacks_unmatched)
    if unpaired:
        lines += ["", f"not paired: {len(result.matching.tasks_unmatched)} task(s), "
                      f"{len(result.matching.callbacks_unmatched)} callback(s) (E805 says which)"]
    return "\n".join(lines) + "\n"


def _connection_lines(result: TraceResult) -> list[str]:
    delays = result.delays
    lines = []
    if delays.connections:
        lines += ["", "connections (delay from publish to receipt min / p50 / p99 / max against the model's delay):"]
    for c in delays.connections:
        ok = ("above the delay" if c.delays.max > c.delay_max else "below the delay" if c.delays.min < c.delay_min
              else "ok")
        lines.append(f"  {c.connection}: {c.delays.count} messages, {_words(c.delays)} in [{fmt_time(c.delay_min)}, "
                     f"{fmt_time(c.delay_max)}] {ok}")
    for what, reason in delays.unpaired:
        lines.append(f"  messages of {what}: not paired with a connection ({reason})")
    return lines


def to_json(result: TraceResult) -> dict[str, Any]:
    rec = result.recording
    model = result.analysis
    return {
        "schema": "verify.trace/1",
        "system": result.system,
        "source": rec.source,
        "paths": list(rec.paths),
        "events": rec.events,
        "partial": list(rec.partial),
        "tasks": [{"task": m.task, "callback": m.callback, "jobs": m.jobs, "execution": _dist(m.execution),
                   "bcet_s": _q(model.task(m.task).bcet), "wcet_s": _q(model.task(m.task).wcet),
                   "intervals": _dist(m.intervals), "mean_period_s": _q(m.mean_period),
                   "configured_period_s": _q(m.configured_period), "jobs_above_wcet": m.overrun_count,
                   "cpu_jobs": m.cpu_jobs, "elapsed": _dist(m.elapsed), "response": _dist(m.response)}
                  for m in result.measured.tasks],
        "chains": [{"chain": c.chain, "missing": c.missing, "reaction_time": _dist(c.reaction_time),
                    "data_age": _dist(c.data_age), "jitter_s": _q(c.jitter),
                    "bounds": {"reaction_time_s": _q(model.chain(c.chain).reaction_time.worst),
                               "data_age_s": _q(model.chain(c.chain).data_age.worst),
                               "jitter_s": _q(model.chain(c.chain).jitter)},
                    "specs": {s.kind + "_s": _q(s.spec) for s in model.chain(c.chain).specs}}
                   for c in result.measured.chains],
        "connections": [{"connection": c.connection, "topics": list(c.topics), "delay": _dist(c.delays),
                         "delay_min_s": _q(c.delay_min), "delay_max_s": _q(c.delay_max)}
                        for c in result.delays.connections],
        "unpaired": {"tasks": [{"task": t, "reason": r} for t, r in result.matching.tasks_unmatched],
                     "links": [{"messages": what, "reason": r} for what, r in result.delays.unpaired],
                     "callbacks": [{"callback": rec.callbacks[k].describe(), "reason": r}
                                   for k, r in result.matching.callbacks_unmatched]},
    }
