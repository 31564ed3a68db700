"""``verify trace --calibrate``: measured execution times and connection delays written into the model
by minimal edits (specs/trace.md §5), as ``synth`` writes its holes (``verify.synth.writeback``): only
the values of ``bcet``, ``wcet`` and ``delay`` change (or, for a task without one, a line is added
before the task's closing brace; for a connection without a delay, ` delay A .. B` at the end of its
statement); every other byte — comments, layout, line endings — stays.

A component's task gets, over the instances measured: ``wcet`` = the greatest measured execution time
times (1 + margin), rounded up to a microsecond; ``bcet`` = the least measured execution time, rounded
down to a microsecond. A connection measured gets ``delay MIN .. MAX`` likewise: the least measured
delay rounded down, the greatest times (1 + margin) rounded up. Only components and systems in the
model's root file are edited; the others are named.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

from ..model import syntax as s
from ..model.system import SystemModel
from ..core.source import SourceFile
from ..synth.writeback import Edit, apply_edits
from .delays import ConnectionMeasure, Delays
from .metrics import Measurements

#: the margin on the measured worst case, unless ``--margin`` says otherwise (specs/trace.md §5)
DEFAULT_MARGIN = Fraction(20, 100)
US = Fraction(1, 10**6)


@dataclass(frozen=True)
class Change:
    component: str  # a connection's change: "a.x -> b.y"
    task: str  # "" for a connection
    what: str  # "bcet" | "wcet" | "delay" (its maximum: ``old`` and ``new``)
    old: Fraction | None
    new: Fraction
    new_min: Fraction | None = None  # a delay's new minimum

    @property
    def subject(self) -> str:
        return f"{self.component}.{self.task}" if self.task else f"connection {self.component}"


@dataclass(frozen=True)
class Calibration:
    text: str
    changes: tuple[Change, ...]
    elsewhere: tuple[str, ...]  # components (and connections: "connection `a.x -> b.y`") not in the root file


def _us(x: Fraction) -> str:
    """A whole number of microseconds as the language writes it."""
    return f"{math.ceil(x / US)} us"


def measured_times(model: SystemModel, measured: Measurements,
                   margin: Fraction) -> dict[tuple[str, str], tuple[Fraction, Fraction]]:
    """(component, task) → (bcet, wcet) from the measurements of every instance of it."""
    out: dict[tuple[str, str], tuple[Fraction, Fraction]] = {}
    for m in measured.tasks:
        if m.execution is None:
            continue
        task = model.task(m.task)
        key = (task.component, task.name)
        low, high = measured_range(m.execution.min, m.execution.max, margin)
        if key in out:
            low, high = min(low, out[key][0]), max(high, out[key][1])
        out[key] = (low, max(high, low))
    return out


def measured_range(low: Fraction, high: Fraction, margin: Fraction) -> tuple[Fraction, Fraction]:
    """[low rounded down, high × (1 + margin) rounded up], to a microsecond."""
    least = math.floor(low / US) * US
    return least, max(math.ceil(high * (1 + margin) / US) * US, least)


def delay_edits(root: s.Module, source: SourceFile, model: SystemModel, measured: tuple[ConnectionMeasure, ...],
                margin: Fraction) -> tuple[list[Edit], list[Change], list[str]]:
    """The edits writing the measured delays into the connections of ``model`` in ``root`` (those in
    another file: named, third)."""
    system = next((sy for sy in root.systems if sy.name.text == model.name), None)
    edits: list[Edit] = []
    changes: list[Change] = []
    elsewhere: list[str] = []
    for c in measured:
        low, high = measured_range(c.delays.min, c.delays.max, margin)
        syntax = next((k for k in system.connections if (str(k.source), str(k.target)) == (c.source, c.target)),
                      None) if system is not None else None
        if syntax is None:
            elsewhere.append(f"connection `{c.connection}`")
            continue
        if (c.delay_min, c.delay_max) == (low, high):
            continue
        text = f"{_us(low)} .. {_us(high)}"
        changes.append(Change(c.connection, "", "delay", c.delay_max if syntax.delay_max is not None else None,
                              high, low))
        if syntax.delay_min is not None and syntax.delay_max is not None:
            start, end = source.map.span_offsets(syntax.delay_min.span.to(syntax.delay_max.span))
            edits.append(Edit(start, end, text))
        else:
            end = source.map.span_offsets(syntax.span)[1]
            edits.append(Edit(end, end, f" delay {text}"))
    return edits, changes, elsewhere


def calibrate(root: s.Module, source: SourceFile, model: SystemModel, measured: Measurements,
              margin: Fraction = DEFAULT_MARGIN, delays: Delays | None = None) -> Calibration:
    times = measured_times(model, measured, margin)
    edits: list[Edit] = []
    changes: list[Change] = []
    local = {c.name.text: c for c in root.components}
    smap = source.map
    for (component, task_name), (bcet, wcet) in times.items():
        comp = local.get(component)
        task = next((t for t in comp.tasks if t.name.text == task_name), None) if comp is not None else None
        if task is None or task.end.line == task.span.line:
            continue  # (a task on one line is left as it is: named below)
        missing = []
        for what, value, given in (("bcet", bcet, task.bcet), ("wcet", wcet, task.wcet)):
            if given is not None and given.value * s.TIME_UNITS[given.unit] == value:
                continue
            changes.append(Change(component, task_name, what, None if given is None else
                                  given.value * s.TIME_UNITS[given.unit], value))
            if given is None:
                missing.append(f"{what} {_us(value)}")
                continue
            start, end = smap.span_offsets(given.span)
            edits.append(Edit(start, end, _us(value)))
        if missing:
            line_start = smap.line_start(task.end.line)
            indent = smap.line_text(task.end.line)[:task.end.column - 1]
            edits.append(Edit(line_start, line_start, "".join(f"{indent}  {m}  // measured\n" for m in missing)))
    edited = {(c.component, c.task) for c in changes}
    elsewhere = tuple(sorted({c for c, t in times
                              if c not in local or ((c, t) not in edited and _one_line(local[c], t))}))
    more, connections, not_here = delay_edits(root, source, model, delays.connections if delays else (), margin)
    text = apply_edits(source.text, sorted(edits + more, key=lambda e: e.start))
    return Calibration(text, tuple(changes + connections), elsewhere + tuple(not_here))


def _one_line(component: s.Component, task_name: str) -> bool:
    task = next((t for t in component.tasks if t.name.text == task_name), None)
    return task is not None and task.end.line == task.span.line
