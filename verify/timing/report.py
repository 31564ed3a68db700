"""Render an ``AnalysisResult``: a versioned JSON document and the outline text view.

JSON (``to_json``), schema ``"verify.analysis/1"`` (the JSON Schema is ``JSON_SCHEMA``; specs/timing.md
§8 describes every field). Every exact number is an object ``{"exact": "1/30", "decimal": null}``:
``exact`` is the rational as ``p/q`` (or an integer), ``decimal`` its finite decimal expansion when one
exists (``"0.025"``), else null. No floats. Times are seconds, rates hertz, factors unitless. A
number that is not bounded is ``null``.

Text, short (``to_brief``, what ``analyze`` prints): the verdict of every spec by its bound first, then
each core's utilisation, each task's rate and response times, and the chain table. Text, whole
(``to_text``, ``analyze --explain``): the outline of the system — every task with its rate and response
times, every connection marked over- or undersampled with its factor — then a chain table (worst/best
reaction time and data age, jitter, spec, margin, dominating hop) and each chain's per-step breakdown
naming the rule that produced each term, and the verdicts last.
"""
from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction
from typing import Any

from ..model.activations import KINDS
from ..model.units import fmt_number, fmt_time
from . import AnalysisResult, TaskTiming
from .chains import SPEC_WORDS, Bound, ChainBounds, Step, Term
from .rates import EventModel, LinkSampling, RateInterval
from .rta import CoreLoad, percent

SCHEMA = "verify.analysis/1"


# ================================================================== JSON


def exact(value: Fraction | int | None) -> dict[str, str | None] | None:
    """``{"exact": "p/q", "decimal": "0.25" | null}``, or None (unbounded)."""
    if value is None:
        return None
    if not isinstance(value, Fraction):
        value = Fraction(value)
    num, den = value.numerator, value.denominator  # (a Fraction is in lowest terms)
    text = str(num) if den == 1 else f"{num}/{den}"
    decimal = fmt_number(value)
    return {"exact": text, "decimal": None if "/" in decimal else decimal}


def _interval(rate: RateInterval | None) -> dict[str, Any] | None:
    return None if rate is None else {"min": exact(rate.low), "max": exact(rate.high)}


def _activation(t: TaskTiming) -> dict[str, Any]:
    a = t.activation
    return {
        "kind": a.kind,
        "period": exact(a.period),
        "phase": exact(a.phase),
        "interarrival": None if a.interarrival is None else {"min": exact(a.interarrival[0]),
                                                             "max": exact(a.interarrival[1])},
        "rate": _interval(a.rate),
        "rate_derivation": a.derivation,
        "trigger_port": a.trigger_port,
        "mode": a.mode,
        "prescaler": a.prescaler,
        "sources": [{"member": s.member, "port": s.port, "writer": s.writer,
                     "connection": s.link.source if s.link else None} for s in a.sources],
        "in_trigger_cycle": a.in_cycle,
    }


def _events(e: EventModel) -> dict[str, Any]:
    return {
        "silent": e.silent,
        "period_min": exact(e.period_min), "jitter_min": exact(e.jitter_min),
        "period_max": exact(e.period_max), "jitter_max": exact(e.jitter_max),
        "first_max": exact(e.first_max),
        "a_min": exact(e.a_min), "a_max": exact(e.a_max), "sampling_wait": exact(e.sampling_wait),
    }


def _task(t: TaskTiming) -> dict[str, Any]:
    r = t.response
    return {
        "id": t.id, "core": t.core, "priority": t.priority, "kind": t.kind,
        **({"executor": t.executor} if t.executor is not None else {}),
        "bcet": exact(t.bcet), "wcet": exact(t.wcet),
        "activation": _activation(t),
        "event_model": _events(t.events),
        "bcrt": exact(r.bcrt), "wcrt": exact(r.wcrt), "wcrt_computed": exact(r.wcrt_computed),
        "wcrt_rule": r.rule, "bcrt_rule": "bcet",
        "deadline": exact(r.deadline), "deadline_rule": r.deadline_rule,
        "blocking": exact(r.blocking), "hold": exact(r.hold),
        "busy_window_jobs": r.busy_jobs, "critical_job": r.critical_job,
        "interferers": list(r.interferers),
        "schedulable": r.schedulable, "failure": r.failure,
    }


def _core(c: CoreLoad) -> dict[str, Any]:
    return {"name": c.core, "utilisation": exact(c.utilisation),
            "percent": None if c.utilisation is None else percent(c.utilisation),
            "overloaded": c.overloaded, "tasks": list(c.tasks)}


def _link(s: LinkSampling) -> dict[str, Any]:
    return {
        "source": s.source, "target": s.target, "writer": s.writer, "reader": s.reader,
        "writer_rate": _interval(s.writer_rate), "reader_rate": _interval(s.reader_rate),
        "relation": s.relation, "by_trigger": s.by_trigger,
        "oversampled": s.oversampled, "oversampling_factor": exact(s.oversampling),
        "undersampled": s.undersampled, "undersampling_factor": exact(s.undersampling),
    }


def _term(term: Term | None) -> dict[str, Any] | None:
    if term is None:
        return None
    return {"rule": term.rule, "value": exact(term.value), "note": term.note or None,
            "parts": [{"name": n, "value": exact(v)} for n, v in term.parts]}


def _step(n: int, s: Step) -> dict[str, Any]:
    return {"index": n, "kind": s.kind, "label": s.label, "writer": s.writer, "reader": s.reader,
            "source": s.source, "target": s.target, "reaction_time": _term(s.reaction),
            "data_age": _term(s.data_age), "data_age_non_reduced": _term(s.data_age_non_reduced),
            "best": exact(s.best), "best_term": _term(s.best_term),
            "best_non_reduced": _term(s.best_non_reduced)}


def _bound(b: Bound) -> dict[str, Any]:
    return {"worst": exact(b.worst), "best": exact(b.best), "jitter": exact(b.jitter), "rule": b.rule}


def _chain(c: ChainBounds) -> dict[str, Any]:
    return {
        "name": c.name, "tasks": list(c.tasks), "problem": c.problem,
        "hops": [_step(n, s) for n, s in enumerate(c.steps)],
        "bounds": {"reaction_time": _bound(c.reaction_time),
                   "reaction_time_reduced": _bound(c.reaction_time_reduced),
                   "data_age_reduced": _bound(c.data_age_reduced),
                   "data_age_non_reduced": _bound(c.data_age_non_reduced)},
        "data_age_variant": c.data_age_variant,
        "specs": [{"kind": s.kind, "variant": s.variant, "spec": exact(s.spec), "bound": exact(s.bound),
                   "margin": exact(s.margin), "ok": s.ok, "status": s.status} for s in c.specs],
        "dominating": {"reaction_time": c.dominating_reaction, "data_age": c.dominating_age,
                       "data_age_reduced": c.dominating_data_age,
                       "data_age_non_reduced": c.dominating_data_age_non_reduced},
    }


def to_json(result: AnalysisResult) -> dict[str, Any]:
    """The analysis as a JSON-ready dict following ``JSON_SCHEMA`` (schema "verify.analysis/1")."""
    return {
        "schema": SCHEMA,
        "system": result.system,
        "data_age_variant": result.data_age_variant,
        "converged": result.converged,
        "rounds": result.rounds,
        "cores": [_core(c) for c in result.cores],
        "tasks": [_task(t) for t in result.tasks],
        "links": [_link(s) for s in result.links],
        "chains": [_chain(c) for c in result.chains],
        "diagnostics": [{"code": d.code, "severity": d.severity.value, "message": d.message,
                         "file": d.span.file, "line": d.span.line, "column": d.span.column}
                        for d in result.diagnostics],
    }


_NUM = {"oneOf": [{"type": "null"}, {"type": "object", "required": ["exact", "decimal"],
                                      "additionalProperties": False,
                                      "properties": {"exact": {"type": "string", "pattern": r"^-?\d+(/\d+)?$"},
                                                     "decimal": {"type": ["string", "null"]}}}]}
_STR = {"type": ["string", "null"]}
_INTERVAL = {"oneOf": [{"type": "null"}, {"type": "object", "required": ["min", "max"],
                                           "properties": {"min": _NUM, "max": _NUM}}]}
_TERM = {"oneOf": [{"type": "null"}, {"type": "object", "required": ["rule", "value", "parts"],
                                       "properties": {"rule": {"type": "string"}, "value": _NUM, "note": _STR,
                                                      "parts": {"type": "array", "items": {
                                                          "type": "object", "required": ["name", "value"],
                                                          "properties": {"name": {"type": "string"},
                                                                         "value": _NUM}}}}}]}
_BOUND = {"type": "object", "required": ["worst", "best", "jitter", "rule"],
          "properties": {"worst": _NUM, "best": _NUM, "jitter": _NUM, "rule": {"type": "string"}}}


def _obj(required: dict[str, Any], **extra: Any) -> dict[str, Any]:
    return {"type": "object", "required": sorted(required), "properties": required, **extra}


JSON_SCHEMA: dict[str, Any] = _obj({
    "schema": {"const": SCHEMA},
    "system": {"type": "string"},
    "data_age_variant": {"enum": ["reduced", "non-reduced"]},
    "converged": {"type": "boolean"},
    "rounds": {"type": "integer"},
    "cores": {"type": "array", "items": _obj({"name": {"type": "string"}, "utilisation": _NUM, "percent": _STR,
                                              "overloaded": {"type": "boolean"},
                                              "tasks": {"type": "array", "items": {"type": "string"}}})},
    "tasks": {"type": "array", "items": _obj({
        "id": {"type": "string"}, "core": {"type": "string"}, "priority": {"type": "integer"},
        "kind": {"enum": ["preemptive", "cooperative"]}, "bcet": _NUM, "wcet": _NUM,
        "activation": _obj({"kind": {"enum": list(KINDS)}, "period": _NUM,
                            "phase": _NUM, "rate": _INTERVAL, "rate_derivation": {"type": "string"},
                            "trigger_port": _STR, "mode": _STR,
                            "prescaler": {"type": ["integer", "null"]},
                            "sources": {"type": "array"}, "interarrival": {"type": ["object", "null"]},
                            "in_trigger_cycle": {"type": "boolean"}}),
        "event_model": _obj({k: _NUM for k in ("period_min", "jitter_min", "period_max", "jitter_max",
                                               "first_max", "a_min", "a_max", "sampling_wait")}
                            | {"silent": {"type": "boolean"}}),
        "bcrt": _NUM, "wcrt": _NUM, "wcrt_computed": _NUM, "wcrt_rule": {"type": "string"},
        "bcrt_rule": {"type": "string"}, "deadline": _NUM, "deadline_rule": {"type": "string"},
        "blocking": _NUM, "hold": _NUM, "busy_window_jobs": {"type": ["integer", "null"]},
        "critical_job": {"type": ["integer", "null"]}, "interferers": {"type": "array"},
        "schedulable": {"type": "boolean"}, "failure": _STR})},
    "links": {"type": "array", "items": _obj({
        "source": {"type": "string"}, "target": {"type": "string"}, "writer": {"type": "string"},
        "reader": {"type": "string"}, "writer_rate": _INTERVAL, "reader_rate": _INTERVAL,
        "relation": {"enum": ["matched", "oversampled", "undersampled", "varies", "unknown"]},
        "by_trigger": {"type": "boolean"}, "oversampled": {"type": "boolean"}, "oversampling_factor": _NUM,
        "undersampled": {"type": "boolean"}, "undersampling_factor": _NUM})},
    "chains": {"type": "array", "items": _obj({
        "name": {"type": "string"}, "tasks": {"type": "array", "items": {"type": "string"}}, "problem": _STR,
        "hops": {"type": "array", "items": _obj({
            "index": {"type": "integer"}, "kind": {"enum": ["first", "hop", "last"]},
            "label": {"type": "string"}, "writer": _STR, "reader": {"type": "string"}, "source": _STR,
            "target": _STR, "reaction_time": _TERM, "data_age": _TERM, "data_age_non_reduced": _TERM,
            "best": _NUM, "best_term": _TERM, "best_non_reduced": _TERM})},
        "bounds": _obj({k: _BOUND for k in ("reaction_time", "reaction_time_reduced", "data_age_reduced",
                                            "data_age_non_reduced")}),
        "data_age_variant": {"enum": ["reduced", "non-reduced"]},
        "specs": {"type": "array", "items": _obj({
            "kind": {"enum": ["reaction_time", "data_age", "jitter"]}, "variant": {"type": "string"},
            "spec": _NUM, "bound": _NUM, "margin": _NUM, "ok": {"type": "boolean"},
            "status": {"enum": ["proved", "undecided"]}})},
        "dominating": _obj({k: {"type": ["integer", "null"]} for k in ("reaction_time", "data_age",
                                                                         "data_age_reduced",
                                                                         "data_age_non_reduced")})})},
    "diagnostics": {"type": "array", "items": _obj({"code": {"type": "string"}, "severity": {"type": "string"},
                                                    "message": {"type": "string"}},)},
}, **{"$schema": "https://json-schema.org/draft/2020-12/schema", "title": SCHEMA})
# a callback of a ROS 2 executor names it (specs/timing.md §9); other tasks have no such key
JSON_SCHEMA["properties"]["tasks"]["items"]["properties"]["executor"] = {"type": "string"}


# ================================================================== text


def _t(value: Fraction | None) -> str:
    return fmt_time(value)


def _rate_text(t: TaskTiming) -> str:
    a = t.activation
    if a.period is not None:
        how = f"{a.kind} {fmt_time(a.period)}" + (f" phase {fmt_time(a.phase)}" if a.phase is not None else "")
    elif a.interarrival is not None:
        how = f"{a.kind} {fmt_time(a.interarrival[0])} .. {fmt_time(a.interarrival[1])}"
    elif a.trigger_port is not None:
        how = f"trigger {a.trigger_port}" + (f" every {a.prescaler}" if a.prescaler != 1 else "")
    else:
        how = "synthesis hole"
    writers = [s.writer for s in a.sources if s.writer]
    source = " from " + ", ".join(writers) if writers else ""
    if a.rate is None:
        return f"{how}: rate {a.derivation}{source}"
    rate = str(a.rate)
    derived = "" if a.timed or a.derivation == rate else f" = {a.derivation}"
    return f"{how}: {rate}{derived}{source}"


def _a_max_text(e: EventModel) -> str:
    """``A⁺`` with its derivation ``δ⁺(2) = P⁺ + J⁺`` (§5.2), and ``W⁺ = max(A⁺, F)`` when larger."""
    if e.silent:
        return "A⁺ unbounded (never activated)"
    text = f"A⁺ {_t(e.a_max)} = P⁺ {_t(e.period_max)} + J⁺ {_t(e.jitter_max)} (§5.2 δ⁺(2))"
    if e.sampling_wait is not None and e.a_max is not None and e.sampling_wait > e.a_max:
        text += f"   W⁺ {_t(e.sampling_wait)} = F, the latest first activation (§5.2 max(A⁺, F))"
    return text


def _task_line(t: TaskTiming) -> str:
    r = t.response
    section = "§6.2" if t.executor is None else "§9.4" if r.rule.startswith("multi_threaded") else "§9.3"
    wcrt = _t(r.wcrt) + (f" ({r.rule}, {section})" if r.wcrt is not None else f" ({r.failure or 'unbounded'})")
    thread = f"executor {t.executor}, " if t.executor is not None else ""
    line = (f"  {t.id}  [{t.core}, {thread}priority {t.priority}{', cooperative' if t.kind == 'cooperative' else ''}]"
            f"  {_rate_text(t)} (§5.1)\n"
            f"      C {_t(t.bcet)} .. {_t(t.wcet)}   R {_t(r.bcrt)} (§6.4 bcet) .. {wcrt}"
            f"   deadline {_t(r.deadline)} ({r.deadline_rule}, §6.2)"
            f"\n      {_a_max_text(t.events)}")
    if r.blocking:
        line += f"   blocking {_t(r.blocking)} (§6.3)"
    return line


def sampling_marks(s: LinkSampling, prescaled: bool = True) -> list[str]:
    """``oversampled ×F`` and ``undersampled ×F`` (∞: unbounded) as far as they apply, for every
    renderer (the report, the diagram, the HTML page, the editor); without ``prescaled``, an
    undersampling that is only a trigger's prescaler is left out."""
    marks = []
    if s.oversampled:
        marks.append(f"oversampled ×{'∞' if s.oversampling is None else fmt_number(s.oversampling)}")
    if s.undersampled and (prescaled or not s.by_trigger):
        marks.append(f"undersampled ×{'∞' if s.undersampling is None else fmt_number(s.undersampling)}")
    return marks


def _link_line(s: LinkSampling) -> str:
    if s.relation == "matched":
        what = "matched" + (" (triggered by this port)" if s.by_trigger else "")
    elif s.relation == "unknown":
        what = "rates not bounded"
    else:
        what = " or ".join(sampling_marks(s))
        if s.by_trigger:
            what += " (trigger prescaler)"
        elif not (s.writer_rate and s.reader_rate and s.writer_rate.is_point and s.reader_rate.is_point):
            what += " (worst direction of the rate intervals)"
    w = "?" if s.writer_rate is None else str(s.writer_rate)
    r = "?" if s.reader_rate is None else str(s.reader_rate)
    return f"  {s.source} -> {s.target}  ({s.writer} {w} → {s.reader} {r}): {what} (§5.3)"


def _spec_cell(c: ChainBounds, kind: str) -> tuple[str, str]:
    check = next((s for s in c.specs if s.kind == kind), None)
    if check is None:
        return "-", "-"
    margin = "unbounded" if check.margin is None else _t(check.margin)
    if not check.ok:
        margin += " not proved"
    return f"<= {_t(check.spec)}", margin




def _spec_verdicts(result: AnalysisResult) -> list[str]:
    """One line per spec with its verdict by the bound, after a count: the end of the text view."""
    checks = [(c, s) for c in result.chains for s in c.specs]
    if not checks:
        return ["no latency specs"]
    proved = sum(s.ok for _, s in checks)
    head = (f"{len(checks)} spec{'s' if len(checks) != 1 else ''}: {proved} proved by the bound, "
            f"{len(checks) - proved} not proved by the bound")
    if proved < len(checks):
        head += " (a bound above a spec proves nothing either way: `prove` decides it)"
    rows = []
    for c, s in checks:
        if s.bound is None:
            verdict = "not proved by the bound: no bound"
        elif s.ok:
            verdict = f"proved by the bound: {_t(s.bound)}, margin {_t(s.margin)}"
        else:
            verdict = f"not proved by the bound: {_t(s.bound)} exceeds it by {_t(s.bound - s.spec)}"
        rows.append([f"chain {c.name}: {SPEC_WORDS.get(s.kind, s.kind)}", f"<= {_t(s.spec)}", verdict])
    return [head] + _table(rows)


def _dominating(c: ChainBounds, index: int | None) -> str:
    if index is None:
        return "-"
    return c.steps[index].label


def _chain_rows(c: ChainBounds) -> list[list[str]]:
    age = c.data_age
    rows = []
    for name, bound, kind, dom in (("reaction time", c.reaction_time, "reaction_time", c.dominating_reaction),
                                   (f"data age ({c.data_age_variant})", age, "data_age", c.dominating_age)):
        spec, margin = _spec_cell(c, kind)
        rows.append([c.name, name, _t(bound.worst), _t(bound.best), _t(bound.jitter), spec, margin,
                     _dominating(c, dom), bound.rule])
    if any(s.kind == "jitter" for s in c.specs):
        spec, margin = _spec_cell(c, "jitter")
        rows.append([c.name, f"jitter ({c.data_age_variant})", _t(c.jitter), "", "", spec, margin, "",
                     "§7.5 worst − best data age"])
    return rows


def _table(rows: list[list[str]]) -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return ["  " + "  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows]


def _parts_text(parts: Iterable[tuple[str, Fraction | None]]) -> str:
    """``a 1 ms + b 2 ms − c 3 ms``: a part with a negative value is subtracted."""
    out = ""
    for n, (name, value) in enumerate(parts):
        if value is not None and value < 0:
            out += f"{' ' if n else ''}− {name} {_t(-value)}"
        else:
            out += f"{' + ' if n else ''}{name} {_t(value)}"
    return out


def _term_text(term: Term) -> str:
    parts = _parts_text(term.parts)
    note = f"; {term.note}" if term.note else ""
    return f"{_t(term.value)} by {term.rule}: {parts or 'nothing'}{note}"


def _breakdown(c: ChainBounds) -> list[str]:
    lines = [f"  chain {c.name}: " + " -> ".join(c.tasks)]
    if c.problem:
        return lines + [f"    not analysed: {c.problem}"]
    for n, step in enumerate(c.steps):
        marks = []
        if n == c.dominating_reaction:
            marks.append("dominates reaction time")
        if n == c.dominating_data_age:
            marks.append("dominates data age (reduced)")
        if n == c.dominating_data_age_non_reduced:
            marks.append("dominates data age (non-reduced)")
        head = f"    [{n}] {step.label}" + (f"  ({', '.join(marks)})" if marks else "")
        lines.append(head)
        if step.reaction is not None:
            lines.append(f"        reaction  {_term_text(step.reaction)}")
        if step.data_age is not None:
            lines.append(f"        data age  {_term_text(step.data_age)}")
        if step.data_age_non_reduced is not None:
            lines.append(f"        non-reduced data age adds  {_term_text(step.data_age_non_reduced)}")
        lines.append(f"        best      {_term_text(step.best_term)}")
        if step.best_non_reduced is not None:
            lines.append(f"        non-reduced best adds  {_term_text(step.best_non_reduced)}")
    for name, bound in (("reaction time", c.reaction_time), ("reaction time (reduced)", c.reaction_time_reduced),
                        ("data age (reduced)", c.data_age_reduced),
                        ("data age (non-reduced)", c.data_age_non_reduced)):
        lines.append(f"    {name} {_t(bound.worst)} by {bound.rule}; best {_t(bound.best)} "
                     f"(§7.5 Σ best terms{' + least read gap' if 'non-reduced' in name else ''})")
    return lines


def to_text(result: AnalysisResult) -> str:
    """The outline view: tasks with rates and response times, connections with sampling factors,
    the chain table and each chain's breakdown with the rule behind every term."""
    out = [f"system {result.system}  (analysis {SCHEMA}; data age {result.data_age_variant}; "
           f"{'converged' if result.converged else 'NOT converged'} after {result.rounds} round"
           f"{'s' if result.rounds != 1 else ''}, §6.5)", "", "cores (utilisation Σ C⁺·f⁺, §6.1)"]
    for c in result.cores:
        u = "unbounded" if c.utilisation is None else f"{fmt_number(c.utilisation)} ({percent(c.utilisation)})"
        out.append(f"  {c.core}  utilisation {u}{'  OVERLOADED' if c.overloaded else ''}: " + ", ".join(c.tasks))
    out += ["", "tasks"] + [_task_line(t) for t in result.tasks]
    if result.links:
        out += ["", "connections"] + [_link_line(s) for s in result.links]
    if result.chains:
        header = ["chain", "latency", "worst", "best", "jitter", "spec", "margin", "dominating hop", "rule"]
        rows = [header] + [row for c in result.chains for row in _chain_rows(c)]
        out += ["", "chains"] + _table(rows)
        for ch in result.chains:
            out += [""] + _breakdown(ch)
    if result.diagnostics:
        out += ["", f"{len(result.diagnostics)} problem{'s' if len(result.diagnostics) != 1 else ''}: "
                + ", ".join(sorted({d.code for d in result.diagnostics}))]
    out += [""] + _spec_verdicts(result)
    return "\n".join(out)


def _brief_task_row(t: TaskTiming) -> list[str]:
    r = t.response
    where = t.core + (f", executor {t.executor}" if t.executor is not None else "")
    rate = "?" if t.activation.rate is None else str(t.activation.rate)
    worst = _t(r.wcrt) if r.wcrt is not None else (r.failure or "unbounded")
    deadline = "" if r.wcrt is None or r.deadline is None else ("" if r.wcrt <= r.deadline else "  > deadline")
    return [t.id, where, str(t.priority), rate, f"{_t(r.bcrt)} .. {worst}{deadline}"]


def _brief_chain_rows(c: ChainBounds) -> list[list[str]]:
    return [row[:7] for row in _chain_rows(c)]


def to_brief(result: AnalysisResult) -> str:
    """The short view: the verdict of every spec first, then the cores' loads, one line per task (rate,
    response time) and the chain table; ``to_text`` is the whole derivation (``analyze --explain``)."""
    out = [f"system {result.system}  (data age {result.data_age_variant}"
           f"{'' if result.converged else '; NOT converged'})", ""]
    out += _spec_verdicts(result)
    if result.diagnostics:
        out += ["", f"{len(result.diagnostics)} problem{'s' if len(result.diagnostics) != 1 else ''}: "
                + ", ".join(sorted({d.code for d in result.diagnostics})) + " (on standard error)"]
    out += ["", "cores"]
    for c in result.cores:
        u = "unbounded" if c.utilisation is None else percent(c.utilisation)
        out.append(f"  {c.core}  utilisation {u}{'  OVERLOADED' if c.overloaded else ''}")
    out += ["", "tasks"] + _table([["task", "core", "priority", "rate", "response time"]]
                                  + [_brief_task_row(t) for t in result.tasks])
    if result.chains:
        header = ["chain", "latency", "worst", "best", "jitter", "spec", "margin"]
        out += ["", "chains"] + _table([header] + [row for c in result.chains for row in _brief_chain_rows(c)])
    out += ["", "(`verify analyze --explain`: the derivation of every number, with the rules of specs/timing.md)"]
    return "\n".join(out)


__all__ = ["JSON_SCHEMA", "SCHEMA", "exact", "to_brief", "to_json", "to_text"]
