"""The summary of a synthesis: text for people, JSON (schema ``verify.synth/1``) for programs.

Both show every chosen value (with the hole it fills), every spec with its bound and margin under
the chosen configuration, the utilisation of every core, the objective and whether its optimum is
proven, and what the search did. Everything is exact and deterministic: no wall-clock times.

JSON schema ``verify.synth/1``::

    {"schema": "verify.synth/1", "file": str, "system": str,
     "status": "sat" | "unsat" | "undecided", "optimal": bool,
     "objective": [{"name", "sense": "min" | "max", "value": number | null, "unit": "fraction" | "s"}],
     "choices": [{"task", "hole", "value", "kind": "timer" | "trigger", "period": number | null,
                  "port": str | null, "prescaler": int | null}],
     "specs": [{"chain", "kind", "spec": number, "bound": number | null, "margin": number | null, "ok"}],
     "cores": [{"name", "utilisation": number | null, "percent": str | null}],
     "core": [{"key", "kind", "text", "label", "tasks": [str], "file", "line", "column"}],
     "hints": [str], "reason": str | null, "established": [str],
     "output": {"dsl": str | null, "diff": str | null, "written": str | null},
     "search": {...counters...}, "diagnostics": [verify.diagnostics/1 items]}

A number is ``{"exact": "p/q", "decimal": "0.25" | null}`` as in ``verify.analysis/1``; times are
seconds. Choices are listed in source order.
"""
from __future__ import annotations

from fractions import Fraction
from typing import Any

from ..outputs.rendering import diagnostic_json
from ..timing.report import exact
from ..timing.rta import percent
from ..model.units import fmt_number, fmt_time
from .candidates import describe_hole
from .driver import SynthResult

SCHEMA = "verify.synth/1"


def _value_text(kind: str, value: Fraction | None) -> str:
    if value is None:
        return "unbounded"
    if kind == "utilisation":
        return f"{fmt_number(value)} ({percent(value)})"
    return fmt_time(value)


def objective_line(result: SynthResult) -> str:
    if not result.goals:
        return "none (any configuration that meets every constraint)"
    parts = [f"{g.name} {_value_text(g.kind, v)}" for g, v in zip(result.goals, result.values)]
    text = ", then ".join(parts)
    if result.status != "sat" and result.status != "undecided":
        return text
    if result.optimal:
        return f"{text} — proven optimal (a strictly better value is unsatisfiable)"
    return f"{text} — not proven optimal ({result.reason or 'the search stopped early'})"


def _choice_rows(result: SynthResult) -> list[tuple[str, str, str]]:
    rows: list[tuple[str, str, str]] = []
    problem = result.problem
    for task in (result.model.tasks if result.model is not None else ()):
        cand = result.choices.get(task.id)
        if cand is None:
            continue
        rows.append((task.id, describe_hole(problem.choices[task.id]) if problem else "?", cand.text()))
    return rows


def _table(rows: list[list[str]], indent: str = "  ") -> list[str]:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return [(indent + "  ".join(c.ljust(w) for c, w in zip(r, widths))).rstrip() for r in rows]


def to_text(result: SynthResult) -> str:
    """The summary table (for a satisfiable or undecided result with a configuration)."""
    head = {"sat": "satisfiable", "unsat": "unsatisfiable", "undecided": "undecided"}[result.status]
    lines = [f"synth {result.system}: {head}"]
    rows = _choice_rows(result)
    if rows:
        lines += ["", "choices"] + _table([[t, h, "->", v] for t, h, v in rows])
    elif result.model is not None:
        lines += ["", "choices", "  (no holes: the configuration is checked as written)"]
    if result.analysis is not None:
        spec_rows = [["chain", "spec", "bound", "worst case", "margin"]]
        for chain in result.analysis.chains:
            for sp in chain.specs:
                spec_rows.append([chain.name, sp.kind, f"<= {fmt_time(sp.spec)}", fmt_time(sp.bound),
                                  fmt_time(sp.margin)])
        if len(spec_rows) > 1:
            lines += ["", "specs"] + _table(spec_rows)
        lines += ["", "cores"] + _table([[c.core, "unbounded" if c.utilisation is None else
                                          f"{fmt_number(c.utilisation)} ({percent(c.utilisation)})"]
                                         for c in result.analysis.cores])
        lines += ["", f"objective  {objective_line(result)}"]
    stats = result.stats
    lines.append(f"search     {stats.get('candidates', 0)} candidate values ({stats.get('pruned', 0)} pruned), "
                 f"{stats.get('solver_calls', 0)} solver calls, {stats.get('analyses', 0)} analyses, "
                 f"{stats.get('lemmas', 0)} lemmas, rlimit {stats.get('rlimit_used', 0)}"
                 + (f", {stats['enumerated']} configurations enumerated" if "enumerated" in stats else ""))
    return "\n".join(lines) + "\n"


def to_json(result: SynthResult, file: str, *, dsl: str | None = None, diff: str | None = None,
            written: str | None = None) -> dict[str, Any]:
    problem = result.problem
    choices = []
    for task, hole, _ in _choice_rows(result):
        act = result.choices[task].activation
        port = act.trigger_port
        choices.append({"task": task, "hole": hole, "value": act.as_written(), "kind": act.kind,
                        "period": exact(act.strict_period), "port": port,
                        "prescaler": act.release_every if port is not None else None})
    specs, cores = [], []
    if result.analysis is not None:
        specs = [{"chain": ch.name, "kind": sp.kind, "spec": exact(sp.spec), "bound": exact(sp.bound),
                  "margin": exact(sp.margin), "ok": sp.ok} for ch in result.analysis.chains for sp in ch.specs]
        cores = [{"name": c.core, "utilisation": exact(c.utilisation),
                  "percent": None if c.utilisation is None else percent(c.utilisation)} for c in result.analysis.cores]
    core = [{"key": st.key, "kind": st.kind, "text": st.text, "label": st.label, "tasks": list(st.tasks),
             "file": st.span.file if st.span.line > 0 else None, "line": st.span.line or None,
             "column": st.span.column or None} for st in result.core]
    return {
        "schema": SCHEMA,
        "file": file,
        "system": result.system,
        "status": result.status,
        "optimal": result.optimal,
        "objective": [{"name": g.name, "sense": g.sense, "value": exact(v),
                       "unit": "fraction" if g.kind == "utilisation" else "s"}
                      for g, v in zip(result.goals, result.values or (None,) * len(result.goals))],
        "choices": choices,
        "specs": specs,
        "cores": cores,
        "core": core,
        "hints": list(result.explanation.hints) if result.explanation is not None else [],
        "reason": result.reason,
        "established": list(result.established),
        "output": {"dsl": dsl, "diff": diff, "written": written},
        "search": dict(result.stats),
        "diagnostics": [diagnostic_json(d) for d in result.diagnostics],
        "candidates_per_choice": {k: len(v.candidates) for k, v in problem.choices.items()} if problem else {},
    }
