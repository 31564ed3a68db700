"""A model that does not load only for want of what calibration writes or leaves to the integrator — a
task without `wcet` (E217), a task without a priority (E213) or a core (E214), as `verify import caret`
writes models — stood in for by one that loads, so that `verify trace --calibrate` can pair the trace's
callbacks with its tasks and measure them (specs/trace.md §5). The stand-in is the root file with each
gap filled by a placeholder (a `wcet` of the task's `bcet`, else 1 us; `priority 1`; a core of its own);
it is never shown or written: the calibration edits the file as written.
"""
from __future__ import annotations

from collections.abc import Iterable

from ..core.diagnostics import Diagnostic
from ..core.source import SourceFile
from ..frontend.fmt import format_quantity
from ..model import syntax as s
from ..synth.writeback import Edit, apply_edits

#: the errors a stand-in fills: no `wcet`, no priority, no core
GAPS = frozenset({"E217", "E213", "E214"})


def only_gaps(diagnostics: Iterable[Diagnostic]) -> bool:
    """Whether the errors among ``diagnostics`` are gaps only (and there is one)."""
    errors = [d for d in diagnostics if d.severity.value == "error"]
    return bool(errors) and all(d.code in GAPS for d in errors)


def _core_name(module: s.Module) -> str:
    taken = {c.name.text for sy in module.systems for c in sy.cores}
    name, k = "calibration_core", 1
    while name in taken:
        k += 1
        name = f"calibration_core{k}"
    return name


def stand_in_text(module: s.Module, source: SourceFile) -> str:
    """The root file's text with every gap of its components and systems filled by a placeholder."""
    core = _core_name(module)
    edits: list[Edit] = []
    for comp in module.components:
        for task in comp.tasks:
            if task.wcet is None:
                given = format_quantity(task.bcet) if task.bcet is not None else "1 us"
                at = source.map.span_offsets(task.end)[0]
                edits.append(Edit(at, at, f" wcet {given} "))
    for sy in module.systems:
        needed = False
        for inst in sy.instances:
            for b in inst.bindings:
                fill = ""
                if b.executor is None and b.priority is None:
                    fill += " priority 1"
                if b.executor is None and b.core is None and inst.core is None:
                    fill += f" on {core}"
                    needed = True
                if fill:
                    at = source.map.span_offsets(b.task.span)[1]
                    edits.append(Edit(at, at, fill))
        if needed:
            at = source.text.index("{", source.map.span_offsets(sy.name.span)[1]) + 1
            edits.append(Edit(at, at, f" core {core} "))
    return apply_edits(source.text, sorted(edits, key=lambda e: e.start))
