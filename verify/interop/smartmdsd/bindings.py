"""The system side of the SmartMDSD import: each task's binding (core, priority, activation) from its
activity architecture node, and the cause-effect chains (specs/interop.md, "SmartMDSD")."""
from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import Protocol

from ...core.diagnostics import DiagnosticSink
from ...model.units import fmt_number, fmt_time
from .read import Activity, ActivityArch, Chain, Component, Instance, Name, Node, Port

Link = tuple[str, Port, str, Port]

#: the core of activities without a ``cpuAffinity`` (Linux may run them anywhere)
UNPINNED = "unpinned"


class ImportContext(Protocol):
    """What the bindings and chains read of the import under way (``to_vfy``'s builder): where to report,
    the names as the language spells them, the activity architecture and its nodes; ``unpinned`` is set
    when a task is placed on the ``UNPINNED`` core."""

    unpinned: bool

    @property
    def sink(self) -> DiagnosticSink: ...

    @property
    def name(self) -> Callable[[Name], str]: ...

    @property
    def activity_arch(self) -> ActivityArch | None: ...

    @property
    def nodes(self) -> dict[str, Node]: ...

    @property
    def by_node(self) -> dict[str, tuple[str, Activity]]:  # node -> (instance, activity it configures)
        ...


def _last(name: Name) -> str:
    return name.text.rsplit(".", 1)[-1]


def node_of(b: ImportContext, inst: Instance, act: Activity) -> Node | None:
    for node_name, (inst_name, a) in b.by_node.items():
        if inst_name == inst.name.text and a is act:
            return b.nodes[node_name]
    return None


def reads(act: Activity) -> set[str]:
    return {link.port.text for link in act.links} | ({act.handler_of.text} if act.handler_of else set())


def binding(b: ImportContext, inst: Instance, comp: Component, act: Activity, links: list[Link]) -> tuple[str, str]:
    """(core, the clauses after ``task NAME [on CORE]``) of one task; what is missing is reported (E704)."""
    node = node_of(b, inst, act)
    where = node.name.span if node else act.name.span
    gaps: list[str] = []
    core = _core(b, node, gaps)
    priority = _priority(b, node, gaps)
    activation = _activation(b, inst, comp, act, node, links, gaps)
    if node is None:
        gaps.append("no node in the activity architecture, so no execution time (E217)")
    elif node.handler:
        gaps.append("no execution time: an InputHandlerNode holds none (E217)")
    elif node.max_time is None:
        gaps.append("no executionTime in its node, so no wcet (E217)")
    if gaps:
        b.sink.emit("E704", f"task `{inst.name.text}.{act.name.text}` lacks what the timing model needs", where,
                    "incomplete", notes=gaps,
                    help="complete the SmartMDSD model and import again, or complete the imported file")
    return core, f" priority {priority}{activation}"


def _core(b: ImportContext, node: Node | None, gaps: list[str]) -> str:
    if node is not None and node.affinity is not None:
        cores = {c.text for c, _ in (b.activity_arch.cores if b.activity_arch else ())}
        if _last(node.affinity) in cores:
            return b.name(Name(_last(node.affinity), node.affinity.span))
        b.sink.emit("E702", f"no CPUCore `{node.affinity.text}` in the activity architecture", node.affinity.span,
                    "not found", help="declare it with `CPUCore NAME { coreNumber N }`")
    b.unpinned = True
    gaps.append(f"no cpuAffinity: placed on core `{UNPINNED}`, which every unpinned task shares")
    return UNPINNED


def _priority(b: ImportContext, node: Node | None, gaps: list[str]) -> int:
    if node is not None and node.scheduler_type is not None and node.scheduler_type.text != "FIFO":
        b.sink.emit("E703", f"scheduler type `{node.scheduler_type.text}` has no counterpart: the task is analysed "
                    "under fixed-priority preemptive scheduling (SCHED_FIFO) with its priority",
                    node.scheduler_type.span, "modelled as FIFO", help="use type FIFO for a real-time guarantee")
    if node is not None and node.priority is not None:
        value, span = node.priority
        if value >= 0:
            return value
        b.sink.emit("E705", f"priority {value} is negative", span, "negative", help="give a priority of 0 or more")
    gaps.append("no scheduler priority: priority 0 is assumed (every task without one is equal)")
    return 0


def _activation(b: ImportContext, inst: Instance, comp: Component, act: Activity, node: Node | None,
                links: list[Link], gaps: list[str]) -> str:
    if act.handler_of is not None:  # an input handler runs on every (prescale-th) message of its port
        every = f" every {node.prescale}" if node is not None and node.prescale != 1 else ""
        return f" trigger {b.name(act.handler_of)}{every}"
    src = node.source if node is not None else None
    if src is not None and node is not None:
        if src.kind == "timer" and src.freq is not None:
            return f" timer {_hz(src.freq)}"
        if src.kind == "data" and src.trigger is not None:
            port = _trigger_port(b, inst, act, node, src.trigger, links)
            if port is None:
                gaps.append(f"no port for its trigger input `{src.trigger.text}`, so no activation is written (E207)")
                return ""
            return f" trigger {b.name(port)}" + (f" every {src.prescale}" if src.prescale != 1 else "")
        return _sporadic(b, act, src.min_freq, src.max_freq, gaps)
    default = act.default
    if default is not None and default.kind == "timer" and default.freq is not None:
        return f" timer {_hz(default.freq)}"
    if default is not None and default.kind == "input" and default.port is not None:
        every = f" every {default.prescale}" if default.prescale != 1 else ""
        return f" trigger {b.name(default.port)}{every}"
    if default is not None and default.kind == "observed":
        b.sink.emit("E703", "a DefaultTrigger `ObservedElement` has no counterpart (an activity run by another "
                    "one's completion)", default.span, "not imported",
                    help="configure the activity in the activity architecture")
    if act.constraints is not None and not act.constraints.configurable:
        gaps.append("no activation source, and its rate is fixed, so synth cannot choose one (E207)")
        return ""
    return " activation ?"


def _hz(value: Fraction) -> str:
    return f"{fmt_number(value)} Hz"


def _sporadic(b: ImportContext, act: Activity, low: Fraction | None, high: Fraction | None,
              gaps: list[str]) -> str:
    c = act.constraints
    if high is None and c is not None and c.max_freq is not None:
        high = c.max_freq
    if low is None and c is not None and c.min_freq is not None:
        low = c.min_freq
    if high is None or low is None:
        which = "maxActFreq (its fastest rate)" if high is None else "minActFreq (its slowest rate)"
        gaps.append(f"no {which} in its Sporadic source or its ActivationConstraints, so no activation is "
                    "written (E207)")
        return ""
    return f" sporadic {_hz(low)} .. {_hz(high)}"


def _trigger_port(b: ImportContext, inst: Instance, act: Activity, node: Node, trigger: Name,
                  links: list[Link]) -> Name | None:
    """The in-port of ``inst`` behind trigger input ``trigger`` of ``node``: the connection that carries the
    data flow into it."""
    arch = b.activity_arch
    if arch is None:
        return None
    target = f"{node.name.text}.{_last(trigger)}"
    flows = [f for f in arch.flows if f.destination.text == target]
    if not flows:
        b.sink.emit("E705", f"no DataFlow reaches trigger input `{target}`", trigger.span, "no data flow",
                    help=f"add `DataFlow {{ source NODE destination {target} }}`")
        return None
    flow = flows[0]
    writer = b.by_node.get(_last(flow.source))
    if writer is None:
        if _last(flow.source) not in b.nodes:
            b.sink.emit("E702", f"the source `{flow.source.text}` of a DataFlow is no node of the activity "
                        "architecture", flow.source.span, "not found",
                        help="name an ActivityNode or InputHandlerNode")
        return None  # (a node that configures nothing is reported as such)
    found = [rp for wi, wp, ri, rp in links
             if wi == writer[0] and wp.realized_by is not None and wp.realized_by.text == writer[1].name.text
             and ri == inst.name.text and rp.name.text in reads(act)]
    if not found:
        b.sink.emit("E705", f"data flow `{flow.source.text} -> {target}` has no connection in the component "
                    "architecture into a port the activity reads", flow.span, "no connection",
                    help="connect the writer's OutputPort to an InputPort the activity reads (InputPortLink)")
        return None
    return found[0].name


def chain_text(b: ImportContext, chain: Chain, links: list[Link]) -> str | None:
    tasks: list[tuple[str, Activity]] = []
    for _, ref in chain.links:
        found = b.by_node.get(_last(ref))
        if found is None:
            b.sink.emit("E702", f"chain `{chain.name.text}`: node `{ref.text}` configures no imported activity; "
                        "the chain is not imported", ref.span, "no activity",
                        help="map the node to an activity in the .componentArch")
            return None
        tasks.append(found)
    if len(tasks) < 2:
        b.sink.emit("E705", f"chain `{chain.name.text}` has {len(tasks)} link{'s' if len(tasks) != 1 else ''}: a "
                    "cause-effect chain needs two or more; it is not imported", chain.name.span, "too short",
                    help="list the activities from sensor to actuator in chainLinks")
        return None
    elems = []
    for (wi, wa), (ri, ra) in zip(tasks, tasks[1:]):
        ports = [wp for i, wp, j, rp in links if i == wi and j == ri and wp.realized_by is not None
                 and wp.realized_by.text == wa.name.text and rp.name.text in reads(ra)]
        if not ports:
            b.sink.emit("E705", f"chain `{chain.name.text}`: no connection carries data from `{wi}.{wa.name.text}` "
                        f"to `{ri}.{ra.name.text}`; the chain is not imported", chain.name.span, "broken chain",
                        help="connect an OutputPort the first writes to an InputPort the second reads")
            return None
        elems.append(f"{b.name(Name(wi, chain.name.span))}.{b.name(ports[0].name)}")
    last_inst, last_act = tasks[-1]
    elems.append(f"{b.name(Name(last_inst, chain.name.span))}.{b.name(last_act.name)}")
    specs = []
    if chain.max_response is not None:
        specs.append(f"    reaction_time <= {fmt_time(chain.max_response[0])}")
    if chain.min_response is not None:
        b.sink.emit("E703", "desiredMinResponse has no counterpart (specs bound latencies from above): it is not "
                    "imported", chain.min_response[1], "not imported",
                    help="nothing to do; the best case is reported by `verify analyze`")
    body = " {\n" + "\n".join(specs) + "\n  }" if specs else ""
    return f"  chain {b.name(chain.name)}: {' -> '.join(elems)}{body}"


__all__ = ["binding", "chain_text"]
