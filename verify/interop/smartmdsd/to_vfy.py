"""SmartMDSD models (``read.Files``) as a model of verify's language (specs/interop.md, "SmartMDSD").

One system is imported: its ``.componentArch``, the ``.activityArch`` it uses, the ``.causeEffectChain``
models refining that, and the ``.component`` definitions its instances instantiate. Every construct
with a counterpart is mapped; what has none is reported where it stands (E703), what the timing model
needs but the files do not give is reported too (E704), and the output then says so at that place.
"""
from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Literal

from ...core.diagnostics import DiagnosticSink, Label, Severity
from ...core.sanitize import comment
from ...core.source import Span
from ...model.units import fmt_number, fmt_time
from .bindings import UNPINNED, binding, chain_text
from .read import (Activity, ActivityArch, Chain, ChainModel, Component, ComponentArch, Files, Instance, Name, Node,
                   Port)


def reserved() -> frozenset[str]:
    from ...frontend.grammar import reserved_words

    return reserved_words()


@dataclass
class Imported:
    text: str
    system: str


@dataclass
class _Task:
    instance: str
    activity: Activity
    node: Node | None
    lines: list[str] = field(default_factory=list)


def _hz(value: Fraction) -> str:
    return f"{fmt_number(value)} Hz"


class _Names:
    """SmartMDSD names as names of the language: one that is a keyword here gets a trailing ``_``."""

    def __init__(self, sink: DiagnosticSink):
        self.sink, self.words = sink, reserved()
        self.told: set[str] = set()

    def __call__(self, name: Name) -> str:
        text = name.text
        if text not in self.words:
            return text
        if text not in self.told:
            self.told.add(text)
            self.sink.emit("E703", f"the name `{text}` is a keyword of verify's language: it is imported as "
                           f"`{text}_`", name.span, "renamed", help="rename it in the SmartMDSD model to keep "
                           "the names alike")
        return text + "_"


def select_system(files: Files, name: str | None, sink: DiagnosticSink) -> ComponentArch | None:
    archs = files.component_archs
    if name is not None:
        found = [a for a in archs if a.name.text == name]
        if not found:
            known = ", ".join(sorted(a.name.text for a in archs)) or "none"
            sink.emit("E105", f"no system named `{name}` among the SmartMDSD files (systems: {known})",
                      Span("<command line>", 1, 1, 1, 1), "no such system",
                      help="name one of the SystemComponentArchitecture models with --system")
            return None
        archs = found
    if len(archs) == 1:
        return archs[0]
    if not archs:
        sink.emit("E705", "no .componentArch file among the SmartMDSD files: there is no system to import",
                  Span("<command line>", 1, 1, 1, 1), "no system",
                  help="name the directory that holds the system's .componentArch (and its components)")
        return None
    first = archs[0]
    names = ", ".join(a.name.text for a in archs)
    sink.emit("E705", f"{len(archs)} systems among the SmartMDSD files ({names}): say which one to import",
              first.name.span, "one of several",
              secondary=[Label(a.name.span, "another") for a in archs[1:]],
              help="choose with --system NAME, or name a directory that holds one system")
    return None


class _Builder:
    def __init__(self, files: Files, arch: ComponentArch, sink: DiagnosticSink):
        self.files, self.arch, self.sink = files, arch, sink
        self.name = _Names(sink)
        self.components = {c.name.text: c for c in files.components}
        self.activity_arch = self._activity_arch()
        self.nodes = {n.name.text: n for n in self.activity_arch.nodes} if self.activity_arch else {}
        self.instances: list[tuple[Instance, Component]] = []
        self.by_node: dict[str, tuple[str, Activity]] = {}  # node -> (instance, activity it configures)
        self.tasks: list[_Task] = []
        self.unpinned = False

    # -------------------------------------------------------------- lookups

    def _activity_arch(self) -> ActivityArch | None:
        ref = self.arch.activity_arch
        if ref is None:
            return None
        found = [a for a in self.files.activity_archs if a.name.text == ref.text.rsplit(".", 1)[-1]]
        if not found:
            self.sink.emit("E702", f"the activity architecture `{ref.text}` is not among the SmartMDSD files",
                           ref.span, "not found", help="name the directory that holds its .activityArch too; "
                           "without it every activity keeps its component's default trigger")
            return None
        return found[0]

    def component(self, inst: Instance) -> Component | None:
        comp = self.components.get(inst.component.text.rsplit(".", 1)[-1])
        if comp is None:
            links = sum(1 for c in self.arch.connections
                        if inst.name.text in (c.client.text.split(".")[0], c.server.text.split(".")[0]))
            also = f", nor its {links} connection{'s' if links != 1 else ''}" if links else ""
            self.sink.emit("E702", f"component `{inst.component.text}` is not among the SmartMDSD files: instance "
                           f"`{inst.name.text}` is not imported{also}", inst.component.span, "not found",
                           help="name the directory of its .component file too (directories are searched "
                                "recursively)")
        return comp

    def port(self, ref: Name) -> tuple[str, Port] | None | Literal[False]:
        """The instance and port of ``Instance.Port``; False when the instance is not imported."""
        inst_name, _, port_name = ref.text.partition(".")
        for inst, comp in self.instances:
            if inst.name.text == inst_name:
                for port in comp.ports:
                    if port.name.text == port_name:
                        return inst_name, port
                return None
        return False

    # -------------------------------------------------------------- the parts

    def build(self) -> str:
        for inst in self.arch.instances:
            comp = self.component(inst)
            if comp is not None:
                self.instances.append((inst, comp))
                self.map_nodes(inst, comp)
        self.report_unmapped_nodes()
        self.report_dropped()
        links = self.connections()
        comps = self.component_texts()
        system = self.system_text(links)
        return "\n".join(comps + [system])

    def map_nodes(self, inst: Instance, comp: Component) -> None:
        acts = {a.name.text: a for a in comp.activities}
        for (sub, node), handler in [(m, False) for m in inst.activities] + [(m, True) for m in inst.handlers]:
            act = acts.get(sub.text.rsplit(".", 1)[-1])
            kind = "input handler" if handler else "activity"
            if act is None or (act.handler_of is not None) != handler:
                self.sink.emit("E702", f"component `{comp.name.text}` has no {kind} `{sub.text}`", sub.span,
                               "not found", help=f"name one of the {kind}s of `{comp.name.text}`")
                continue
            if self.activity_arch is None:
                continue
            if node.text not in self.nodes:
                self.sink.emit("E702", f"the activity architecture `{self.activity_arch.name.text}` has no node "
                               f"`{node.text}`", node.span, "not found",
                               help="name one of its ActivityNode or InputHandlerNode elements")
                continue
            if node.text in self.by_node:
                other = self.by_node[node.text]
                self.sink.emit("E705", f"node `{node.text}` configures two activities: "
                               f"`{other[0]}.{other[1].name.text}` "
                               f"and `{inst.name.text}.{act.name.text}`; only the first is configured by it",
                               node.span, "configures a second activity",
                               help="give each activity a node of its own")
                continue
            self.by_node[node.text] = (inst.name.text, act)

    def report_unmapped_nodes(self) -> None:
        if self.activity_arch is None:
            return
        for node in self.activity_arch.nodes:
            if node.name.text not in self.by_node:
                self.sink.emit("E703", f"node `{node.name.text}` configures no activity of the system: it is not "
                               "imported", node.name.span, "configures nothing",
                               help="map it in the .componentArch (`Activity TASK configuration NODE`), or "
                                    "remove it")

    def report_dropped(self) -> None:
        wanted = {self.arch.path} | {c.name.span.file for _, c in self.instances}
        if self.activity_arch is not None:
            wanted.add(self.activity_arch.path)
        wanted |= {m.path for m in self.chain_models()}
        for what, span in self.files.dropped:
            if span.file in wanted:
                self.sink.emit("E703", f"{what} has no counterpart in the timing model: it is not imported", span,
                               "not imported", help="nothing to do: it does not affect timing as modelled "
                                                    "(specs/interop.md lists what is mapped)")

    def chain_models(self) -> list[ChainModel]:
        if self.activity_arch is None:
            return []
        name = self.activity_arch.name.text
        return [m for m in self.files.chain_models if m.activity_arch.text.rsplit(".", 1)[-1] == name]

    # -------------------------------------------------------------- connections

    def connections(self) -> list[tuple[str, Port, str, Port]]:
        """(writer instance, out-port, reader instance, in-port) of every connection."""
        links = []
        for conn in self.arch.connections:
            client, server = self.port(conn.client), self.port(conn.server)
            if client is False or server is False:
                continue  # (an instance not imported: reported with it)
            if client is None or server is None:
                for ref, end in ((conn.client, client), (conn.server, server)):
                    if end is None:
                        self.sink.emit("E702", f"`{ref.text}` is no port of its instance's component", ref.span,
                                       "not found", help="name a port the component declares")
                continue
            (ia, pa), (ib, pb) = client, server
            if {pa.direction, pb.direction} != {"in", "out"}:
                self.sink.emit("E705", f"connection `{conn.client.text} -> {conn.server.text}` joins two "
                               f"{pa.direction}-ports: data cannot flow", conn.span, "no data flow",
                               help="connect an OutputPort with an InputPort")
                continue
            (wi, wp), (ri, rp) = ((ia, pa), (ib, pb)) if pa.direction == "out" else ((ib, pb), (ia, pa))
            links.append((wi, wp, ri, rp))
        return links

    # -------------------------------------------------------------- components

    def component_texts(self) -> list[str]:
        seen: dict[str, Component] = {}
        for _, comp in self.instances:
            seen.setdefault(comp.name.text, comp)
        return [self.component_text(comp) for comp in seen.values()]

    def times(self, comp: Component, act: Activity) -> tuple[Fraction | None, Fraction | None]:
        """The widest (bcet, wcet) the nodes configuring ``act`` give, over every instance of ``comp``."""
        lows, highs, spans = [], [], []
        for node_name, (_, a) in self.by_node.items():
            node = self.nodes[node_name]
            if a is act and node.max_time is not None:
                lows.append(node.min_time if node.min_time is not None else Fraction(0))
                highs.append(node.max_time)
                spans.append(node.time_span or node.name.span)
        if not highs:
            return None, None
        if len(set(highs)) > 1 or len(set(lows)) > 1:
            self.sink.emit("E705", f"the instances of `{comp.name.text}` give `{act.name.text}` different execution "
                           "times: the task takes the widest range", spans[0], "one range",
                           secondary=[Label(s, "another") for s in spans[1:]], severity=Severity.WARNING,
                           help="execution times belong to the component in verify's language: give each "
                                "instance the same")
        return min(lows), max(highs)

    def component_text(self, comp: Component) -> str:
        name = self.name(comp.name)
        lines = [f"// {comment(comp.name.text)}: imported from {comment(os.path.basename(comp.name.span.file))}",
                 f"component {name} {{"]
        for port in comp.ports:
            lines.append(f"  {port.direction} {self.name(port.name)} : {self.type_name(port.service)}")
        for act in comp.activities:
            lines += self.task_text(comp, act)
        lines.append("}")
        return "\n".join(lines) + "\n"

    def type_name(self, service: Name) -> str:
        return self.name(Name(service.text.rsplit(".", 1)[-1], service.span))

    def task_text(self, comp: Component, act: Activity) -> list[str]:
        ports = {p.name.text: p for p in comp.ports}
        lines = ["", f"  task {self.name(act.name)} {{"]
        read = []
        if act.handler_of is not None and self._in_port(ports, act.handler_of, comp):
            read.append(act.handler_of.text)
            lines.append(f"    reads {self.name(act.handler_of)}  // the port this input handler serves")
        for link in act.links:
            if link.port.text in read or not self._in_port(ports, link.port, comp):
                continue
            read.append(link.port.text)
            opts = (["optional"] if link.optional else []) + [
                "oversampling " + ("ok" if link.oversampling_ok else "forbidden"),
                "undersampling " + ("ok" if link.undersampling_ok else "forbidden")]
            lines.append(f"    reads {self.name(link.port)} {' '.join(opts)}")
        produced = [self.name(p.name) for p in comp.ports
                    if p.direction == "out" and p.realized_by and p.realized_by.text == act.name.text]
        if produced:
            lines.append(f"    produces {', '.join(produced)}")
        bcet, wcet = self.times(comp, act)
        if wcet is not None:
            lines.append(f"    bcet {fmt_time(bcet)}")
            lines.append(f"    wcet {fmt_time(wcet)}")
        c = act.constraints
        if c is not None:
            fixed = "" if c.configurable else " fixed"
            if c.min_freq is not None and c.max_freq is not None:
                bounds = _hz(c.min_freq) if c.min_freq == c.max_freq else f"{_hz(c.min_freq)} .. {_hz(c.max_freq)}"
                lines.append(f"    activation {bounds}{fixed}")
            elif c.min_freq is not None:
                lines.append(f"    activation min {_hz(c.min_freq)}{fixed}")
            elif c.max_freq is not None:
                lines.append(f"    activation max {_hz(c.max_freq)}{fixed}")
            elif not c.configurable:
                self.sink.emit("E703", f"`configurable=false` of {comp.name.text}.{act.name.text} names no frequency: "
                               "there is no rate to fix, so the rate stays changeable", c.span, "no frequency",
                               help="add minActFreq and maxActFreq")
        lines.append("  }")
        return lines

    def _in_port(self, ports: dict[str, Port], ref: Name, comp: Component) -> bool:
        port = ports.get(ref.text)
        if port is None or port.direction != "in":
            self.sink.emit("E702", f"`{ref.text}` is no InputPort of `{comp.name.text}`: the read is not imported",
                           ref.span, "not an in-port", help="name an InputPort of the component")
            return False
        return True

    # -------------------------------------------------------------- the system

    def system_text(self, links: list[tuple[str, Port, str, Port]]) -> str:
        body: list[str] = []
        inst_lines: list[str] = []
        for inst, comp in self.instances:
            bindings = [binding(self, inst, comp, act, links) for act in comp.activities]
            cores = {core for core, _ in bindings}
            shared = cores.pop() if len(cores) == 1 else None
            on = f" on {shared}" if shared else ""
            inst_lines.append(f"  instance {self.name(inst.name)} : {self.name(comp.name)}{on} {{")
            for act, (core, text) in zip(comp.activities, bindings):
                where = "" if shared else f" on {core}"
                inst_lines.append(f"    task {self.name(act.name)}{where}{text}")
            inst_lines.append("  }")
        core_names = [self.name(c) for c, _ in (self.activity_arch.cores if self.activity_arch else ())]
        if self.unpinned:
            core_names.append(UNPINNED)
        body += [f"  core {c} policy fixed_priority" for c in core_names]
        body += [""] + inst_lines
        if links:
            body.append("")
            body += [f"  connect {self.name(Name(wi, p.name.span))}.{self.name(wp.name)} -> "
                     f"{self.name(Name(ri, p.name.span))}.{self.name(rp.name)}"
                     for wi, wp, ri, rp in links for p in (wp,)]
        chains = list(self.chain_texts(links))
        if chains:
            body += [""] + chains
        header = (f"// imported from {comment(os.path.basename(self.arch.path))} by `verify import smartmdsd` "
                  "(specs/interop.md)\n")
        return header + f"system {self.name(self.arch.name)} {{\n" + "\n".join(body) + "\n}\n"

    def chain_texts(self, links: list[tuple[str, Port, str, Port]]) -> Iterable[str]:
        for model in self.chain_models():
            for chain in model.chains:
                text = chain_text(self, chain, links)
                if text is not None:
                    yield text


def import_system(files: Files, system: str | None, sink: DiagnosticSink) -> Imported | None:
    """The system's model in verify's language, or None after an error that leaves nothing to import."""
    arch = select_system(files, system, sink)
    if arch is None:
        return None
    builder = _Builder(files, arch, sink)
    return Imported(builder.build(), arch.name.text)


__all__ = ["Chain", "Imported", "import_system", "select_system"]
