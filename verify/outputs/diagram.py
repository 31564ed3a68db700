"""The system as a picture: Graphviz DOT of a configured (or analysed) system (``verify graph``).

Each instance is a box: its name and component, its core; in-ports on the left, its tasks in the middle
(activation source, rate, priority, response time), out-ports on the right. Data flows from out-port to
in-port; a connection that activates its reader says so (``triggers``, ``every k`` for a prescaler), a
sampled one that is over- or undersampled is drawn orange with the factor (§5.3 of specs/timing.md).
Each chain has a colour: its hops are drawn in it (parallel lines where chains share a connection), and
the legend gives each chain's reaction time and data age against its specs, with the margin. The text
is deterministic; Graphviz's ``dot`` lays it out (SVG, PNG) when present.
"""
from __future__ import annotations

import html
import shutil
import subprocess
from collections.abc import Iterable
from fractions import Fraction

from ..model.system import CompoundDecl, SystemModel, TaskModel
from ..timing import AnalysisResult
from ..timing.rates import LinkSampling
from ..timing.report import sampling_marks
from ..model.units import fmt_number, fmt_time

#: one colour per chain, in source order (ColorBrewer Dark2, then repeated)
CHAIN_COLOURS = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d", "#666666")
SAMPLING_COLOUR = "#b2182b"  # over/undersampling: dark red, dashed
FONT = "DejaVu Sans"


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _id(name: str) -> str:
    return '"' + name.replace("\\", "\\\\").replace('"', '\\"') + '"'


def chain_colour(index: int) -> str:
    return CHAIN_COLOURS[index % len(CHAIN_COLOURS)]


# ------------------------------------------------------------------ instances


def _activation_text(task: TaskModel, analysis: AnalysisResult | None) -> str:
    how = task.activation.describe()
    if analysis is not None:
        rate = analysis.task(task.id).rate
        how += f" · {rate if rate is not None else 'rate unbounded'}"
    return how


def _task_cell(task: TaskModel, analysis: AnalysisResult | None) -> str:
    detail = (f"executor {task.executor} · " if task.executor is not None else "") + f"priority {task.priority}"
    detail += " · cooperative" if task.kind == "cooperative" else ""
    detail += f" · C ≤ {fmt_time(task.wcet)}"
    if analysis is not None:
        wcrt = analysis.task(task.id).wcrt
        detail += f" · R ≤ {fmt_time(wcrt)}"
    return (f'<TD PORT="t_{_e(task.name)}" BGCOLOR="#ffffff" ALIGN="LEFT"><B>{_e(task.name)}</B><BR ALIGN="LEFT"/>'
            f'<FONT POINT-SIZE="9">{_e(_activation_text(task, analysis))}</FONT><BR ALIGN="LEFT"/>'
            f'<FONT POINT-SIZE="9">{_e(detail)}</FONT><BR ALIGN="LEFT"/></TD>')


def _port_column(ports: Iterable[str], side: str) -> str:
    rows = "".join(f'<TR><TD PORT="{side}_{_e(p)}" BGCOLOR="#eef3fb">{_e(p)}</TD></TR>' for p in ports)
    return f'<TABLE BORDER="0" CELLBORDER="1" CELLSPACING="2">{rows}</TABLE>' if rows else ""


def _instance_node(model: SystemModel, name: str, analysis: AnalysisResult | None) -> str:
    inst = model.instance(name)
    comp = model.component(inst.component)
    tasks = [model.task(t) for t in inst.tasks]
    cores = sorted({t.core for t in tasks}) or ([inst.core] if inst.core else [])
    task_rows = "".join(f"<TR>{_task_cell(t, analysis)}</TR>" for t in tasks)
    inputs = _stack(_port_column([p.name for p in comp.in_ports], "in"), _compounds(comp.compounds))
    label = (f'<TABLE BORDER="1" CELLBORDER="0" CELLSPACING="0" CELLPADDING="4" BGCOLOR="#f7f7f7">'
             f'<TR><TD COLSPAN="3" BGCOLOR="#dfe6f0"><B>{_e(name)}</B> : {_e(comp.name)}'
             f'<BR/><FONT POINT-SIZE="9">{_e(", ".join(cores))}</FONT></TD></TR>'
             f'<TR><TD VALIGN="MIDDLE">{inputs}</TD>'
             f'<TD><TABLE BORDER="0" CELLBORDER="1" CELLSPACING="2">{task_rows}</TABLE></TD>'
             f'<TD VALIGN="MIDDLE">{_port_column([p.name for p in comp.out_ports], "out")}</TD></TR></TABLE>')
    return f"  {_id(name)} [shape=plain, label=<{label}>];"


def _stack(*tables: str) -> str:
    """The non-empty ``tables`` one above the other (a cell of an HTML label holds one table)."""
    parts = [t for t in tables if t]
    if len(parts) <= 1:
        return "".join(parts)
    rows = "".join(f"<TR><TD>{t}</TD></TR>" for t in parts)
    return f'<TABLE BORDER="0" CELLBORDER="0" CELLSPACING="0">{rows}</TABLE>'


def _compounds(compounds: Iterable[CompoundDecl]) -> str:
    rows = "".join(f'<TR><TD><FONT POINT-SIZE="9">{_e(c.name)} = '
                   f'{_e((" & " if c.mode == "and" else " | ").join(c.members))}</FONT></TD></TR>' for c in compounds)
    return f'<TABLE BORDER="0" CELLBORDER="0" CELLSPACING="0">{rows}</TABLE>' if rows else ""


# ------------------------------------------------------------------ connections


def _sampling_text(s: LinkSampling) -> str | None:
    return " / ".join(sampling_marks(s, prescaled=False)) or None


def _edges(model: SystemModel, analysis: AnalysisResult | None) -> list[str]:
    on_chain: dict[tuple[str, str], list[int]] = {}
    for index, chain in enumerate(model.chains):
        for hop in chain.hops:
            on_chain.setdefault((hop.link.source, hop.link.target), []).append(index)
    sampling: dict[str, list[LinkSampling]] = {}
    for s in analysis.links if analysis is not None else ():
        sampling.setdefault(s.target, []).append(s)
    lines = []
    for link in model.links:
        src_inst, src_port = link.source.split(".", 1)
        dst_inst, dst_port = link.target.split(".", 1)
        labels, warn = [], False
        for reader in link.readers:
            act = model.task(reader).activation
            if act.listens_to(dst_port):
                via = "" if act.trigger_port == dst_port else f" via {act.trigger_port}"
                every = f" every {act.release_every}" if act.release_every != 1 else ""
                labels.append(f"triggers {reader.split('.', 1)[1]}{via}{every}")
        for s in sampling.get(link.target, ()):
            text = _sampling_text(s)
            if text:
                labels.append(f"{s.reader.split('.', 1)[1]}: {text}")
                warn = True
        if link.delay_max:
            labels.append(f"delay {fmt_time(link.delay_min)} .. {fmt_time(link.delay_max)}")
        chains = on_chain.get((link.source, link.target), [])
        colour = ":".join(chain_colour(i) for i in chains) if chains else (SAMPLING_COLOUR if warn else "#555555")
        attrs = [f'color="{colour}"', f"penwidth={2.2 if chains else 1.2}"]
        if warn and not chains:
            attrs.append("style=dashed")
        if labels:
            font = SAMPLING_COLOUR if warn else "#333333"
            attrs.append(f'label=<<FONT POINT-SIZE="9" COLOR="{font}">{"<BR/>".join(_e(x) for x in labels)}</FONT>>')
        lines.append(f"  {_id(src_inst)}:{_id('out_' + src_port)}:e -> {_id(dst_inst)}:{_id('in_' + dst_port)}:w "
                     f"[{', '.join(attrs)}];")
    return lines


# ------------------------------------------------------------------ legend


def _bound_text(kind: str, bound: Fraction | None, spec: Fraction | None, ok: bool | None) -> str:
    text = f"{kind} ≤ {fmt_time(bound)}"
    if spec is not None:
        mark = "✓" if ok else "✗"
        margin = "" if bound is None else f", margin {fmt_time(spec - bound)}"
        text += f" against spec {fmt_time(spec)} {mark}{margin}"
    return text


def _legend(model: SystemModel, analysis: AnalysisResult | None) -> list[str]:
    rows = []
    for index, chain in enumerate(model.chains):
        colour = chain_colour(index)
        lines = [" → ".join(chain.tasks)]
        if analysis is not None:
            bounds = analysis.chain(chain.name)
            checks = {c.kind: c for c in bounds.specs}
            for kind, title, bound in (("reaction_time", "reaction time", bounds.reaction_time.worst),
                                       ("data_age", "data age", bounds.data_age_reduced.worst)):
                check = checks.get(kind)
                lines.append(_bound_text(title, bound, check.spec if check else None, check.ok if check else None))
        text = '<BR ALIGN="LEFT"/>'.join(_e(x) for x in lines)
        rows.append(f'<TR><TD BGCOLOR="{colour}" WIDTH="14"> </TD><TD ALIGN="LEFT"><B>{_e(chain.name)}</B>'
                    f'<BR ALIGN="LEFT"/><FONT POINT-SIZE="9">{text}</FONT><BR ALIGN="LEFT"/></TD></TR>')
    if analysis is not None:
        loads = ", ".join(f"{c.core} U = {fmt_number(c.utilisation) if c.utilisation is not None else 'unbounded'}"
                          for c in analysis.cores)
        rows.append(f'<TR><TD COLSPAN="2" ALIGN="LEFT"><FONT POINT-SIZE="9">{_e(loads)}</FONT></TD></TR>')
    if not rows:
        return []
    title = f'<TR><TD COLSPAN="2" BGCOLOR="#dfe6f0"><B>{_e(model.name)}</B></TD></TR>'
    return [f'  "legend" [shape=plain, label=<<TABLE BORDER="1" CELLBORDER="0" CELLSPACING="2" CELLPADDING="3">'
            f"{title}{''.join(rows)}</TABLE>>];"]


def _grid_of_unconnected(model: SystemModel, per_row: int = 4) -> list[str]:
    """Instances without any connection, in rows of ``per_row`` (invisible edges), not one long column."""
    linked = {p.split(".", 1)[0] for lk in model.links for p in (lk.source, lk.target)}
    alone = [inst.name for inst in model.instances if inst.name not in linked]
    return [f"  {_id(a)} -> {_id(b)} [style=invis];" for row in range(0, len(alone), per_row)
            for a, b in zip(alone[row:row + per_row], alone[row + 1:row + per_row])]


def to_dot(model: SystemModel, analysis: AnalysisResult | None = None) -> str:
    """The DOT text of ``model`` (with the analysis' rates, response times and chain bounds if given)."""
    lines = [f"digraph {_id(model.name)} {{", "  rankdir=LR;", "  newrank=true;", "  nodesep=0.35;",
             "  ranksep=0.9;", f'  graph [fontname="{FONT}", fontsize=11];',
             f'  node [fontname="{FONT}", fontsize=11];', f'  edge [fontname="{FONT}", fontsize=9, arrowsize=0.7];']
    lines += [_instance_node(model, inst.name, analysis) for inst in model.instances]
    lines += _edges(model, analysis)
    lines += _grid_of_unconnected(model)
    lines += _legend(model, analysis)
    lines.append("}")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ layout


class GraphvizMissing(Exception):
    """Graphviz's ``dot`` is not installed."""


class GraphvizFailed(Exception):
    """Graphviz's ``dot`` did not lay the picture out (a crash, a limit of its own)."""


def layout(dot_text: str, fmt: str) -> bytes:
    """``dot_text`` laid out by Graphviz as ``fmt`` ("svg", "png" or "pdf")."""
    dot = shutil.which("dot")
    if dot is None:
        raise GraphvizMissing("Graphviz's `dot` is not installed")
    done = subprocess.run([dot, f"-T{fmt}"], input=dot_text.encode("utf-8"), capture_output=True, timeout=120,
                          check=False)
    if done.returncode != 0:
        why = done.stderr.decode("utf-8", "replace").strip()[:300] or f"exit status {done.returncode}"
        raise GraphvizFailed(f"Graphviz's `dot` failed: {why}")
    return done.stdout
