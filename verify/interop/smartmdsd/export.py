"""A configured system as SmartMDSD models (specs/interop.md, "SmartMDSD export").

The configuration — each task's activation source, priority, core and execution times, and the chains
with their reaction-time specs — goes into a new ``.activityArch`` and ``.causeEffectChain``. The
``.componentArch`` maps every task to its node: with ``origin`` (the SmartMDSD files the system was
imported from) it is the original text with only the missing ``Activity … configuration …;`` lines
added (and a ``usingActivityArchitecture`` when it had none), and the original's node names are kept;
without it, it is written from the model. What SmartMDSD cannot hold is E706 (nothing is written) or,
where dropping it leaves a sound model or a value must be rounded, E707.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

from ...core.diagnostics import DiagnosticSink
from ...model.system import SystemModel, TaskModel
from ...core.source import Span
from .read import ComponentArch, Files
from .bindings import UNPINNED


@dataclass
class Exported:
    files: dict[str, str]  # file name -> text


def _decimal(value: Fraction, what: str, where: Span, sink: DiagnosticSink) -> str:
    """An Xtext EDouble (``20.0``, ``37.5``): exact when the value is a terminating decimal, else rounded
    to 9 places (E707)."""
    scaled = value * 10**9
    if scaled.denominator != 1:
        sink.emit("E707", f"{what} {value} Hz is no terminating decimal: SmartMDSD holds decimals only, so it is "
                  "written rounded to 9 places", where, "rounded",
                  help="choose a rate whose decimal ends (a period of 25 ms is 40.0 Hz; 30 ms is 33.33… Hz)")
    n = round(scaled)
    whole, frac = divmod(n, 10**9)
    text = f"{whole}.{str(frac).rjust(9, '0')}".rstrip("0")
    return text + "0" if text.endswith(".") else text


def _time(seconds: Fraction, up: bool, what: str, where: Span, sink: DiagnosticSink) -> str:
    """An integer time in sec, ms or us (the largest that holds it exactly); else rounded to us, up for a
    worst case and down for a best case (E707)."""
    for factor, unit in ((1, "sec"), (1000, "ms"), (10**6, "us")):
        v = seconds * factor
        if v.denominator == 1:
            return f"{v.numerator} {unit}"
    v = seconds * 10**6
    rounded = math.ceil(v) if up else math.floor(v)
    sink.emit("E707", f"{what} is not a whole number of microseconds: written as {rounded} us", where, "rounded",
              help="SmartMDSD's times are integers of sec, ms or us")
    return f"{rounded} us"


class _Exporter:
    def __init__(self, model: SystemModel, origin: Files | None, sink: DiagnosticSink):
        self.model, self.origin, self.sink = model, origin, sink
        self.arch: ComponentArch | None = None
        self.handlers: set[str] = set()  # task ids that are input handlers
        self.node: dict[str, str] = {}  # task id -> node name
        if origin is not None:
            self._from_origin(origin)
        taken = set(self.node.values())
        for t in model.tasks:
            if t.id not in self.node:
                name = base = f"{t.instance}_{t.name}"
                k = 2
                while name in taken:
                    name, k = f"{base}_{k}", k + 1
                taken.add(name)
                self.node[t.id] = name
        ref = self.arch.activity_arch if self.arch is not None else None
        self.arch_name = ref.text.rsplit(".", 1)[-1] if ref is not None else model.name

    def _from_origin(self, origin: Files) -> None:
        found = [a for a in origin.component_archs if a.name.text == self.model.name]
        if not found:
            self.sink.emit("E706", f"no SmartMDSD system `{self.model.name}` among the --from files",
                           self.model.span, "not found", help="name the directory the system was imported from")
            return
        self.arch = arch = found[0]
        comps = {c.name.text: c for c in origin.components}
        known = {i.name.text for i in arch.instances}
        for ours in self.model.instances:
            if ours.name not in known:
                self.sink.emit("E706", f"instance `{ours.name}` is not in the SmartMDSD system `{arch.name.text}`: "
                               "the export writes configuration, not structure", ours.span, "not in SmartMDSD",
                               help="add the ComponentInstance in SmartMDSD first")
        for theirs in arch.instances:
            comp = comps.get(theirs.component.text.rsplit(".", 1)[-1])
            for act in comp.activities if comp else ():
                if act.handler_of is not None:
                    self.handlers.add(f"{theirs.name.text}.{act.name.text}")
            for sub, node in theirs.activities + theirs.handlers:
                self.node[f"{theirs.name.text}.{sub.text.rsplit('.', 1)[-1]}"] = node.text.rsplit(".", 1)[-1]

    # -------------------------------------------------------------- .activityArch

    def activity_arch(self) -> str:
        m = self.model
        lines = [f"ActivityArchitectureModel {self.arch_name} {{"]
        numbers = {c.name: i for i, c in enumerate(m.cores, 1)}
        for core in m.cores:
            if core.name != UNPINNED:
                lines += [f"\tCPUCore {core.name} {{", f"\t\tcoreNumber {numbers[core.name]}", "\t}", ""]
        for t in m.tasks:
            lines += self.node_text(t) + [""]
        for link in m.links:
            for reader in link.readers:
                port = link.target.split(".", 1)[1]
                if self._input_kind(m.task(reader), port) is not None:
                    lines += ["\tDataFlow {", f"\t\tsource {self.node[link.writer]}",
                              f"\t\tdestination {self.node[reader]}.{port}", "\t}"]
        return "\n".join(lines).rstrip() + "\n}\n"

    def _input_kind(self, t: TaskModel, port: str) -> str | None:
        if self.model.link_into(f"{t.instance}.{port}") is None or port not in {r.port for r in t.reads}:
            return None
        act = t.activation
        return "TriggerInputNode" if act.trigger_port == port else "RegisterInputNode"

    def node_text(self, t: TaskModel) -> list[str]:
        name, act = self.node[t.id], t.activation
        if t.id in self.handlers:
            port = act.single_port
            if port is None:
                self.sink.emit("E706", f"`{t.id}` is an input handler: it runs on its port's messages, so it cannot "
                               "have this activation in SmartMDSD", t.span, "not a data trigger",
                               help="activate it with `trigger PORT [every K]`")
                return []
            self._lost(t)
            self.sink.emit("E707", f"the execution times, priority and core of input handler `{t.id}` have no "
                           "counterpart (an InputHandlerNode holds only a prescaler): not exported", t.span,
                           "not exported", help="keep them in the .vfy model; an import gives the handler none")
            return [f"\tInputHandlerNode {name} {{", f"\t\tinput TriggerInputNode {port}",
                    f"\t\tprescale {act.release_every}", "\t}"]
        lines = [f"\tActivityNode {name} {{"]
        inputs = [(self._input_kind(t, r.port), r.port) for r in t.reads]
        if any(kind for kind, _ in inputs):
            lines.append("\t\tinputs {")
            lines += [f"\t\t\t{kind} {port}" for kind, port in inputs if kind]
            lines.append("\t\t}")
        lines += self.source_text(t)
        if t.core != UNPINNED:
            lines.append(f"\t\tcpuAffinity {t.core}")
        low = _time(t.bcet, False, f"the bcet of `{t.id}`", t.span, self.sink)
        high = _time(t.wcet, True, f"the wcet of `{t.id}`", t.span, self.sink)
        lines += ["\t\texecutionTime {", f"\t\t\tminTime {low}", f"\t\t\tmaxTime {high}", "\t\t}",
                  "\t\tscheduler {", "\t\t\ttype FIFO", f"\t\t\tpriority {t.priority}", "\t\t}", "\t}"]
        self._lost(t)
        return lines

    def _lost(self, t: TaskModel) -> None:
        if t.kind == "cooperative":
            self.sink.emit("E707", f"`{t.id}` is cooperative: SmartMDSD has no cooperative activities, it is "
                           "exported as a preemptive one", t.definition_span, "exported preemptive",
                           help="the exported model is analysed with preemption where the .vfy is not")
        if t.wcrt_bound is not None or t.deadline is not None:
            self.sink.emit("E707", f"the wcrt or deadline of `{t.id}` has no counterpart in SmartMDSD: not exported",
                           t.span, "not exported", help="keep it in the .vfy model")

    def source_text(self, t: TaskModel) -> list[str]:
        act = t.activation
        period, gaps, port = act.strict_period, act.gaps, act.single_port
        if period is not None:
            if act.fixed_phase is not None:
                self.sink.emit("E707", f"the phase of `{t.id}` has no counterpart in SmartMDSD: its timer is "
                               "exported without it (an unknown phase, which the analysis covers)", t.span,
                               "phase dropped", help="nothing to do: every phase is then analysed")
            freq = _decimal(1 / period, f"the rate of `{t.id}`", t.span, self.sink)
            return ["\t\tactivationSource PeriodicTimer {", f"\t\t\tperiodicActFreq {freq} Hz", "\t\t}"]
        if gaps is not None:  # released by time, not strictly periodically
            low = _decimal(1 / gaps[1], f"the slowest rate of `{t.id}`", t.span, self.sink)
            high = _decimal(1 / gaps[0], f"the fastest rate of `{t.id}`", t.span, self.sink)
            return ["\t\tactivationSource Sporadic {", f"\t\t\tminActFreq {low} Hz", f"\t\t\tmaxActFreq {high} Hz",
                    "\t\t}"]
        if port is not None:
            return [f"\t\tactivationSource DataTriggered {port} {{", f"\t\t\tprescale {act.release_every}", "\t\t}"]
        what = "an AND/OR compound trigger" if act.trigger_port is not None else "a synthesis hole"
        self.sink.emit("E706", f"`{t.id}` has {what}: SmartMDSD has no counterpart", t.span, "cannot be exported",
                       help="run synth first" if what.endswith("hole") else "trigger it by one in-port")
        return []

    # -------------------------------------------------------------- .componentArch

    def component_arch(self, sources: dict[str, str]) -> str:
        if self.arch is not None:
            return self._edit_component_arch(sources[self.arch.path])
        m = self.model
        lines = [f"SystemComponentArchitecture {m.name} usingActivityArchitecture {self.arch_name}", "{"]
        for inst in m.instances:
            lines += [f"\tComponentInstance {inst.name} instantiates {inst.component}", "\t{"]
            for port_id in inst.ports:
                port = m.port(port_id)
                used = m.link_into(port_id) if port.direction == "in" else m.links_from(port_id)
                if used:
                    kind = "RequiredService" if port.direction == "in" else "ProvidedService"
                    lines.append(f"\t\t{kind} {port.name}")
            lines += [f"\t\tActivity {m.task(t).name} configuration {self.node[t]};" for t in inst.tasks]
            lines += ["\t}"]
        lines += [f"\tConnection {link.target} -> {link.source}" for link in m.links]
        return "\n".join(lines) + "\n}\n"

    def _edit_component_arch(self, text: str) -> str:
        """The original text with the missing mapping lines inserted before each instance's ``}`` (and a
        ``usingActivityArchitecture`` after the system's name when there is none)."""
        assert self.arch is not None
        lines = text.split("\n")
        inserts: list[tuple[int, int, str]] = []  # (line, column, text)
        mapped = {f"{i.name.text}.{s.text.rsplit('.', 1)[-1]}" for i in self.arch.instances
                  for s, _ in i.activities + i.handlers}
        for inst in self.arch.instances:
            if inst.end is None or inst.name.text not in {i.name for i in self.model.instances}:
                continue
            missing = [t for t in self.model.instance(inst.name.text).tasks if t not in mapped]
            if not missing:
                continue
            indent = lines[inst.name.span.line - 1][: len(lines[inst.name.span.line - 1])
                                                     - len(lines[inst.name.span.line - 1].lstrip())] + "\t"
            new = "".join(f"{indent}{'InputHandler' if t in self.handlers else 'Activity'} "
                          f"{t.split('.', 1)[1]} configuration {self.node[t]};\n" for t in missing)
            line = lines[inst.end.line - 1]
            before = line[: inst.end.column - 1]
            if before.strip():
                inserts.append((inst.end.line, inst.end.column, "\n" + new + indent[:-1]))
            else:
                inserts.append((inst.end.line, 1, new))
        if self.arch.activity_arch is None:
            span = self.arch.name.span
            inserts.append((span.line, span.end_column, f" usingActivityArchitecture {self.arch_name}"))
        for line_no, col, add in sorted(inserts, reverse=True):
            line = lines[line_no - 1]
            lines[line_no - 1] = line[: col - 1] + add + line[col - 1:]
        return "\n".join(lines)

    # -------------------------------------------------------------- .causeEffectChain

    def chains(self) -> str | None:
        m = self.model
        if not m.chains:
            return None
        lines = [f"CuaseEffectChainModel {m.name} refinesActivityArch {self.arch_name} {{"]
        for chain in m.chains:
            links = " -> ".join(f"{'hnd' if t in self.handlers else 'act'}.{self.node[t]}" for t in chain.tasks)
            lines += [f"\tActivityChain {chain.name} {{", f"\t\tchainLinks {{ {links} }}"]
            if chain.reaction_time is not None:
                lines.append(f"\t\tdesiredMaxResponse "
                             f"{self._spec_time(chain.reaction_time, chain.name, chain.span)}")
            for kind, value in (("data_age", chain.data_age), ("jitter", chain.jitter)):
                if value is not None:
                    self.sink.emit("E707", f"the {kind} spec of chain `{chain.name}` has no counterpart in SmartMDSD "
                                   "(only a response time): not exported", chain.span, "not exported",
                                   help="keep checking it with `verify prove` on the .vfy model")
            lines.append("\t}")
        return "\n".join(lines) + "\n}\n"

    def _spec_time(self, seconds: Fraction, chain: str, span: Span) -> str:
        # a spec is rounded down: the exported one is never weaker
        return _time(seconds, False, f"the reaction-time spec of chain `{chain}`", span, self.sink)


def export_system(model: SystemModel, origin: Files | None, origin_text: dict[str, str],
                  sink: DiagnosticSink) -> Exported | None:
    """The SmartMDSD files of a configured system (file name -> text), or None after an E706."""
    for executor in model.executors:  # (SmartMDSD's activities are threads: timing.md §9 has no counterpart)
        sink.emit("E706", f"executor `{executor.name}` is a ROS 2 executor, which SmartMDSD cannot hold: its "
                  "activities are threads of their own", executor.span, "no SmartMDSD counterpart",
                  help="bind the callbacks with a priority and a core to export the system")
    ex = _Exporter(model, origin, sink)
    files = {f"{model.name}.activityArch": ex.activity_arch(),
             f"{model.name}.componentArch": ex.component_arch(origin_text)}
    chains = ex.chains()
    if chains is not None:
        files[f"{model.name}.causeEffectChain"] = chains
    if any(d.code == "E706" for d in sink.items):
        return None
    return Exported(files)
