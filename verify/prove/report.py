"""The proof as text (a table of verdicts, then every counterexample's timeline) and as JSON (schema
``verify.proof/1``), specs/proof.md §8–§9."""
from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

from ..model.system import SystemModel
from ..outputs.rendering import diagnostics_json
from ..timing.report import exact
from ..model.units import fmt_time
from .verdict import ProofResult, Verdict

if TYPE_CHECKING:
    from .trace import Runs

SCHEMA = "verify.proof/1"
COLLAPSE = 20  # more task deadlines than this proved by bound are summarised in one line


def _cell(x: Fraction | None) -> str:
    return "-" if x is None else fmt_time(x)


def _task_proved_by_bound(v: Verdict) -> bool:
    return v.subject == "task" and v.status == "proved" and v.method == "bound"


def to_text(model: SystemModel, proof: ProofResult) -> str:
    from .trace import Runs, to_text as timeline

    counts = {s: sum(v.status == s for v in proof.verdicts) for s in ("proved", "violated", "undecided")}
    lines = [f"system {proof.system}  (proof verify.proof/1; data age {proof.data_age_variant}; "
             f"{proof.explored} scenario{'s' * (proof.explored != 1)} simulated of a budget of {proof.budget})",
             f"{len(proof.verdicts)} properties: {counts['proved']} proved, {counts['violated']} violated, "
             f"{counts['undecided']} undecided", ""]
    rows = [["property", "status", "method", "spec", "bound", "exact worst", "margin"]]
    tasks_by_bound = sum(_task_proved_by_bound(v) for v in proof.verdicts)
    collapse = tasks_by_bound > COLLAPSE
    for v in proof.verdicts:
        if collapse and _task_proved_by_bound(v):
            continue
        exact_cell = _cell(v.exact)
        if v.kind == "jitter" and v.exact is not None:
            exact_cell += " (jitter)"
        margin = _cell(v.margin)
        if v.status == "violated" and v.counterexample is not None:
            margin += f" (run: {fmt_time(v.counterexample.latency)})"
        bound_cell = _cell(v.bound) + (f" (refined {fmt_time(v.refined)})" if v.refined is not None else "")
        rows.append([v.label, v.status, v.method, "<= " + fmt_time(v.spec), bound_cell, exact_cell, margin])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    for r in rows:
        lines.append("  " + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
    if collapse:
        lines.append(f"  ... and {tasks_by_bound} task deadlines proved by bound")
    runs = Runs(model, proof.verdicts)  # (each counterexample scenario run once)
    for v in proof.verdicts:
        if v.counterexample is not None:
            lines += ["", timeline(model, v, runs)]
    return "\n".join(lines) + "\n"


def _location(v: Verdict) -> dict[str, Any] | None:
    s = v.span
    if s.line < 1:
        return None
    return {"file": s.file, "line": s.line, "column": s.column, "end_line": s.end_line, "end_column": s.end_column}


def verdict_json(model: SystemModel, v: Verdict, runs: Runs | None = None) -> dict[str, Any]:
    from .trace import to_json as cex_json

    return {"subject": v.subject, "name": v.name, "kind": v.kind, "variant": v.variant, "spec": exact(v.spec),
            "status": v.status, "method": v.method, "bound": exact(v.bound), "refined_bound": exact(v.refined),
            "exact": exact(v.exact),
            "exact_best": exact(v.exact_best), "margin": exact(v.margin), "explored": v.explored,
            "note": v.note or None, "location": _location(v),
            "counterexample": None if v.counterexample is None else cex_json(model, v, runs)}


def to_json(model: SystemModel, proof: ProofResult) -> dict[str, Any]:
    from .trace import Runs

    runs = Runs(model, proof.verdicts)  # (each counterexample scenario run once)
    doc: dict[str, Any] = {"schema": SCHEMA, "system": proof.system, "data_age_variant": proof.data_age_variant,
           "budget": {"scenarios": proof.budget, "simulated": proof.explored},
           "verdicts": [verdict_json(model, v, runs) for v in proof.verdicts]}
    doc["diagnostics"] = diagnostics_json(list(proof.diagnostics))["diagnostics"]
    doc["summary"] = {s: sum(v.status == s for v in proof.verdicts) for s in ("proved", "violated", "undecided")}
    doc["exit_code"] = proof.exit_code
    return doc
