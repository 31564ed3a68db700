"""Writing a synthesized configuration back into the user's file, and re-checking what was written.

By default only the holes change (``completed_text``): each ``?`` — a period hole with its range, a
prescaler hole with its range, ``activation ?`` — is replaced in the text by the chosen value, and every
other byte stays as the user wrote it (layout, comments, line endings). A timer keeps the unit of its
hole's range (a frequency range gives a frequency), otherwise milliseconds. The edited text must parse
to the syntax tree with the holes filled in (``filled_module``), or nothing is written. With
``canonical=True`` the whole root file is printed by the canonical formatter instead, comments and blank
lines kept (``verify.frontend.fmt``).

Written to another directory (``-o``), the root file's imports are rewritten so that they name the same
files from there (``relocated_imports``): only the quoted file names change.

``recheck`` runs the complete front end (parse, resolve, validate, model) and the timing analysis on
the text exactly as it will be written, with the original imports: the text is printed only if that
analysis accepts it.
"""
from __future__ import annotations

import difflib
import os
from dataclasses import dataclass, replace
from fractions import Fraction
from collections.abc import Mapping

from ..model import syntax as s
from ..api import LoadResult, finish_load
from ..core.diagnostics import DiagnosticSink
from .problem import rejects
from ..frontend.fmt import (
    blank_lines, collect_comments, format_activation, format_module, format_number, format_quantity
)
from ..frontend.loader import Project
from ..model.system import SystemModel
from ..frontend.parse import parse_text
from ..frontend.roots import Refusal, Roots
from ..core.source import SourceFile, Span
from ..timing import AnalysisResult, analyze
from .candidates import Candidate


def _timer_period(period: Fraction, hole: s.Activation) -> s.Quantity:
    unit = "ms"
    if isinstance(hole, s.Timer) and isinstance(hole.period, s.PeriodHole) and hole.period.low is not None:
        low = hole.period.low
        if low.dimension == "frequency":
            return s.Quantity((1 / period) / s.FREQUENCY_UNITS[low.unit], low.unit)
        unit = low.unit
    return s.Quantity(period / s.TIME_UNITS[unit], unit)


def filled_activation(hole: s.Activation, cand: Candidate) -> s.Activation:
    """The syntax of ``cand`` in place of the hole ``hole`` (same span)."""
    act = cand.activation
    period = act.strict_period
    if period is not None:
        phase = hole.phase if isinstance(hole, s.Timer) else None
        return s.Timer(_timer_period(period, hole), phase, hole.span)
    prescaler = s.Number(Fraction(act.release_every))
    if isinstance(hole, s.Trigger):
        return replace(hole, prescaler=prescaler)
    port = act.trigger_port
    assert port is not None  # a candidate that is not a timer is a data trigger
    return s.Trigger(s.Name(port), prescaler, hole.span)


def filled_module(module: s.Module, system: str, choices: Mapping[str, Candidate]) -> s.Module:
    """``module`` with the holes of ``system`` filled from ``choices`` (task id → candidate)."""
    systems = []
    for sy in module.systems:
        if sy.name.text != system:
            systems.append(sy)
            continue
        instances = []
        for inst in sy.instances:
            bindings = []
            for b in inst.bindings:
                cand = choices.get(f"{inst.name.text}.{b.task.text}")
                if cand is not None and b.activations and s.is_hole(b.activations[0]):
                    acts = (filled_activation(b.activations[0], cand),) + b.activations[1:]
                    b = replace(b, activations=acts)
                bindings.append(b)
            instances.append(replace(inst, bindings=tuple(bindings)))
        systems.append(replace(sy, instances=tuple(instances)))
    return replace(module, systems=tuple(systems))


def completed_text(load: LoadResult, system: str, choices: Mapping[str, Candidate], *, canonical: bool = False,
                   imports: Mapping[str, str] | None = None) -> str:
    """The root file with the holes of ``system`` filled: only the holes edited, or (``canonical``) the
    whole file canonically formatted with its comments kept. ``imports`` (``relocated_imports``) gives
    new file names for imports, for a file written elsewhere."""
    root = load.project.root_module
    assert root is not None, "a loaded project has its root module"
    source = load.project.sources[load.project.root]
    filled = _renamed_imports(filled_module(root, system, choices), imports or {})
    if canonical:
        return format_module(filled, collect_comments(source.text), blank_lines(source.text))
    edits = hole_edits(source, root, system, choices) + import_edits(source, root, imports or {})
    edited = apply_edits(source.text, sorted(edits, key=lambda e: e.start))
    again = parse_text(edited, load.project.root, DiagnosticSink())
    if again != filled:  # (a tree compares without its spans)
        raise RuntimeError("filling the holes in the text did not give the configuration chosen")
    return edited


def relocated_imports(module: s.Module, path: str, roots: Roots, target: str) -> dict[str, str | Refusal]:
    """For the root file ``path`` (``module``) written to ``target`` instead: the new file name of each
    import whose name, relative to the importing file, changes — the same file named from ``target``'s
    directory — or why it cannot be named (a file name with a ``"``, which no import can hold). An import
    found in a library directory (``--include``) is found there from anywhere, and keeps its name."""
    renamed: dict[str, str | Refusal] = {}
    for imp in module.imports:
        found = roots.resolve(path, imp.path)
        local = os.path.normpath(os.path.join(os.path.dirname(path), imp.path))
        if isinstance(found, Refusal) or found != local:
            continue
        name = os.path.relpath(os.path.abspath(local), os.path.dirname(os.path.abspath(target)))
        name = name.replace(os.sep, "/")
        if '"' in name or "\n" in name:
            renamed[imp.path] = Refusal("E006", f"import `{imp.path}` cannot be written as a file name relative "
                                        f"to `{target}`", "cannot be renamed", "write the output next to the input")
        elif name != imp.path:
            renamed[imp.path] = name
    return renamed


def import_edits(source: SourceFile, module: s.Module, imports: Mapping[str, str]) -> list[Edit]:
    """One edit per import of ``module`` that ``imports`` renames: its quoted file name."""
    edits = []
    for imp in module.imports:
        if imp.path in imports:
            start, end = source.map.span_offsets(imp.path_span)
            edits.append(Edit(start, end, f'"{imports[imp.path]}"'))
    return edits


def _renamed_imports(module: s.Module, imports: Mapping[str, str]) -> s.Module:
    if not imports:
        return module
    return replace(module, imports=tuple(replace(i, path=imports.get(i.path, i.path)) for i in module.imports))


@dataclass(frozen=True)
class Edit:
    """Replace the text between offsets ``start`` and ``end`` by ``text``."""

    start: int
    end: int
    text: str


def hole_edits(source: SourceFile, module: s.Module, system: str, choices: Mapping[str, Candidate]) -> list[Edit]:
    """One edit per hole of ``system`` in ``module`` that ``choices`` fills, in source order. A comment
    inside the replaced text is kept after the new value."""
    edits = []
    comments = collect_comments(source.text)
    for sy in module.systems:
        if sy.name.text != system:
            continue
        for inst in sy.instances:
            for b in inst.bindings:
                cand = choices.get(f"{inst.name.text}.{b.task.text}")
                if cand is None or not b.activations or not s.is_hole(b.activations[0]):
                    continue
                hole = b.activations[0]
                region, text = _replaced(hole, filled_activation(hole, cand))
                start, end = source.map.span_offsets(region)
                inside = [c for c in comments if region.line <= c.line <= region.end_line
                          and start <= source.map.offset(c.line, c.column) < end]
                text += "".join(" " + c.text + ("\n" if c.ends_line else "") for c in inside)
                edits.append(Edit(start, end, text))
    return sorted(edits, key=lambda e: e.start)


def _replaced(hole: s.Activation, filled: s.Activation) -> tuple[Span, str]:
    """(the part of ``hole`` that is replaced, its new text): the period hole and its range, the
    prescaler hole and its range, or the whole ``activation ?``."""
    if (isinstance(hole, s.Timer) and isinstance(hole.period, s.PeriodHole) and isinstance(filled, s.Timer)
            and isinstance(filled.period, s.Quantity)):
        return hole.period.span, format_quantity(filled.period)
    if (isinstance(hole, s.Trigger) and isinstance(hole.prescaler, s.PrescalerHole) and isinstance(filled, s.Trigger)
            and isinstance(filled.prescaler, s.Number)):
        return hole.prescaler.span, format_number(filled.prescaler.value)
    return hole.span, format_activation(filled)


def apply_edits(text: str, edits: list[Edit]) -> str:
    """``text`` with ``edits`` (in source order, not overlapping) applied."""
    parts, at = [], 0
    for e in edits:
        parts.append(text[at:e.start])
        parts.append(e.text)
        at = e.end
    parts.append(text[at:])
    return "".join(parts)


def recheck(load: LoadResult, system: str,
            text: str) -> tuple[LoadResult | None, SystemModel | None, AnalysisResult | None, list[str]]:
    """Load ``text`` as the root file (imports as before) and analyse ``system``: (LoadResult, model,
    analysis, problems) where ``problems`` lists why it would be rejected (empty: accepted)."""
    sink = DiagnosticSink()
    root = load.project.root
    module = parse_text(text, root, sink)
    if module is None:
        return None, None, None, [f"{d.code}: {d.message}" for d in sink.items]
    modules = (module,) + tuple(m for m in load.project.modules if m.path != root)
    sources = dict(load.project.sources)
    sources[root] = SourceFile(root, text)
    reloaded = finish_load(Project(root, modules, sources), sink)
    if system not in reloaded.models:
        return reloaded, None, None, [f"{d.code}: {d.message}" for d in reloaded.diagnostics] or ["not loaded"]
    model = reloaded.models[system]
    result = analyze(model)
    problems = [f"{d.code}: {d.message}" for d in result.diagnostics if rejects(d)]
    problems += [f"`{c.name}`: {sp.kind} exceeds its spec" for c in result.chains for sp in c.specs if not sp.ok]
    problems += [f"`{t.id}` still has a hole" for t in model.holes]
    return reloaded, model, result, problems


def unified_diff(before: str, after: str, path: str) -> str:
    return "".join(difflib.unified_diff(before.splitlines(keepends=True), after.splitlines(keepends=True),
                                        fromfile=path, tofile=f"{path} (synthesized)"))
