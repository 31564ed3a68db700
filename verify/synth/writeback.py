"""Writing a synthesized configuration back as DSL, and re-checking what was written.

The holes of the root file's system are filled in the syntax tree (``dataclasses.replace``, keeping
each activation's span so comments stay where they were) and the whole root file is printed by the
canonical formatter with the user's comments and blank lines (``verify.fmt``). A timer keeps the
unit of its hole's range (a frequency range gives a frequency), otherwise milliseconds.

``recheck`` runs the complete front end (parse, resolve, validate, model) and the timing analysis on
the text exactly as it will be written, with the original imports: the text is printed only if that
analysis accepts it.
"""
from __future__ import annotations

import difflib
from dataclasses import replace
from fractions import Fraction
from typing import Mapping

from .. import syntax as s
from ..api import LoadResult, _finish
from ..diagnostics import DiagnosticSink
from ..fmt import blank_lines, collect_comments, format_module
from ..loader import Project
from ..parse import parse_text
from ..source import SourceFile
from ..timing import analyze
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
    if cand.kind == "timer":
        phase = hole.phase if isinstance(hole, s.Timer) else None
        return s.Timer(_timer_period(cand.period, hole), phase, hole.span)
    prescaler = s.Number(Fraction(cand.prescaler))
    if isinstance(hole, s.Trigger):
        return replace(hole, prescaler=prescaler)
    return s.Trigger(s.Name(cand.port), prescaler, hole.span)


def _is_hole(act: s.Activation | None) -> bool:
    return (isinstance(act, s.UnknownActivation)
            or (isinstance(act, s.Timer) and isinstance(act.period, s.PeriodHole))
            or (isinstance(act, s.Trigger) and isinstance(act.prescaler, s.PrescalerHole)))


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
                if cand is not None and b.activations and _is_hole(b.activations[0]):
                    acts = (filled_activation(b.activations[0], cand),) + b.activations[1:]
                    b = replace(b, activations=acts)
                bindings.append(b)
            instances.append(replace(inst, bindings=tuple(bindings)))
        systems.append(replace(sy, instances=tuple(instances)))
    return replace(module, systems=tuple(systems))


def completed_text(load: LoadResult, system: str, choices: Mapping[str, Candidate]) -> str:
    """The root file with the holes of ``system`` filled, canonically formatted, comments kept."""
    root = load.project.root_module
    text = load.project.sources[load.project.root].text
    return format_module(filled_module(root, system, choices), collect_comments(text), blank_lines(text))


def recheck(load: LoadResult, system: str, text: str):
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
    reloaded = _finish(Project(root, modules, sources), sink)
    if system not in reloaded.models:
        return reloaded, None, None, [f"{d.code}: {d.message}" for d in reloaded.diagnostics] or ["not loaded"]
    model = reloaded.models[system]
    result = analyze(model)
    problems = [f"{d.code}: {d.message}" for d in result.diagnostics if d.severity.value == "error"]
    problems += [f"`{c.name}`: {sp.kind} exceeds its spec" for c in result.chains for sp in c.specs if not sp.ok]
    problems += [f"`{t.id}` still has a hole" for t in model.holes]
    return reloaded, model, result, problems


def unified_diff(before: str, after: str, path: str) -> str:
    return "".join(difflib.unified_diff(before.splitlines(keepends=True), after.splitlines(keepends=True),
                                        fromfile=path, tofile=f"{path} (synthesized)"))
