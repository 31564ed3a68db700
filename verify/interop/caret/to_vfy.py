"""A CARET architecture in verify's language (specs/interop.md, "CARET").

- a **node** is a component and its one instance; a **callback** a task: a timer callback ``timer
  period``, a subscription callback ``trigger TOPIC`` (reading it);
- a **topic** is an out-port of each node that publishes it (produced by its ``publishes`` callbacks)
  and an in-port of each node that subscribes it, connected;
- a **variable passing** (a callback writes a member another reads) is an out-port of the writer
  connected to an in-port the reader reads: the value is the latest written when the reader starts;
- a ``use_latest_message`` **message context** makes the publishing callbacks read the subscribed
  topic (the latest message when they start); ``callback_chain`` is what the callbacks and passings
  already say;
- an **executor** (single-threaded, static single-threaded or multi-threaded) is an executor, its
  callbacks bound to it; a multi-threaded executor's **callback groups** are groups of their nodes'
  instances (specs/timing.md §9.4); a **named path** a chain through the ports of its nodes.

What the file does not hold — execution times, the executors' cores and priorities — is reported
(E704) and left for the user to write, so ``verify check`` of the output lists it; what has no
counterpart (other executor types, callback groups of a single-threaded executor, which change
nothing there, other message contexts) is reported (E703).
"""
from __future__ import annotations

import functools
import re
from dataclasses import dataclass, field
from fractions import Fraction

from ...core.diagnostics import DiagnosticSink
from ...core.sanitize import comment
from ...model.units import fmt_time
from .read import Architecture, Callback, Group, NamedPath, Node

#: CARET executor types and the kinds of specs/timing.md §9
KINDS = {"single_threaded_executor": "single_threaded", "static_single_threaded_executor": "static_single_threaded",
         "multi_threaded_executor": "multi_threaded"}
#: CARET's callback-group types, which are ours (specs/timing.md §9.4)
GROUP_KINDS = ("mutually_exclusive", "reentrant")


@dataclass
class Imported:
    text: str
    system: str


@functools.lru_cache(maxsize=1)
def _reserved() -> frozenset[str]:
    from ...frontend.grammar import reserved_words

    return reserved_words()


def language_name(ros: str, camel: bool = False, reserved: frozenset[str] | None = None) -> str:
    """A ROS name (``/ns/node``, ``/topic``) as a name of the language, before it is made unique in its
    scope: what ``verify import caret`` names an instance (``ns_node``), a port or, ``camel``, a component;
    ``verify trace`` finds a recorded node's instance and a topic's port by it."""
    base = re.sub(r"[^A-Za-z0-9_]+", "_", ros).strip("_") or "unnamed"
    if camel:
        base = "".join(part[:1].upper() + part[1:] for part in base.split("_") if part) or "Unnamed"
    if base[0].isdigit():
        base = "n" + base
    if base in (_reserved() if reserved is None else reserved):
        base += "_"
    return base


class _Names:
    """ROS names as names of the language, unique within one scope."""

    def __init__(self) -> None:
        self.taken: set[str] = set()
        self.words = _reserved()

    def __call__(self, ros: str, camel: bool = False) -> str:
        base = language_name(ros, camel, self.words)
        name, k = base, 2
        while name in self.taken:
            name, k = f"{base}_{k}", k + 1
        self.taken.add(name)
        return name


@dataclass
class _Node:
    node: Node
    component: str
    instance: str
    tasks: dict[str, str] = field(default_factory=dict)  # callback -> task
    ports: _Names = field(default_factory=_Names)  # the names of the component's members
    topic_in: dict[str, str] = field(default_factory=dict)  # topic -> in-port
    topic_out: dict[str, str] = field(default_factory=dict)  # topic -> out-port
    passing: dict[tuple[str, str], tuple[str, str]] = field(default_factory=dict)  # (w, r) -> (out, in)
    reads: dict[str, list[str]] = field(default_factory=dict)  # callback -> in-ports it reads
    produces: dict[str, list[str]] = field(default_factory=dict)  # callback -> out-ports it produces
    groups: list[tuple[str, str, str]] = field(default_factory=list)  # (name, kind, CARET name), declared
    group_of: dict[str, str] = field(default_factory=dict)  # callback -> its declared group


class _Importer:
    def __init__(self, arch: Architecture, sink: DiagnosticSink):
        self.arch, self.sink = arch, sink
        components, instances = _Names(), _Names()
        self.nodes = {n.name: _Node(n, components(n.name, camel=True), instances(n.name)) for n in arch.nodes}
        self.executor_of: dict[tuple[str, str], str] = {}  # (node, callback) -> executor name
        self.executors: list[tuple[str, str, str]] = []  # (name, kind, source name)

    # ------------------------------------------------------------ nodes

    def build_nodes(self) -> None:
        for n in self.nodes.values():
            tasks = n.ports  # (a component's tasks and ports share one namespace)
            for cb in n.node.callbacks:
                if cb.kind not in ("timer", "subscription"):
                    self.sink.emit("E703", f"callback `{cb.name}` of node `{n.node.name}` is a {cb.kind}, which has "
                                   "no counterpart: it is not imported", cb.span, "no counterpart",
                                   help="only timer and subscription callbacks are modelled")
                    continue
                if cb.key in n.tasks:
                    self.sink.emit("E705", f"node `{n.node.name}` has two callbacks `{cb.name}` of construction order "
                                   f"{cb.order}: the second is not imported", cb.span, "defined twice",
                                   help="tell them apart by `construction_order` (0, 1, …), as CARET writes it")
                    continue
                short = cb.name.rsplit("/", 1)[-1]
                n.tasks[cb.key] = tasks(short if cb.order == 0 else f"{short}_order{cb.order}")
                n.reads[cb.key], n.produces[cb.key] = [], []
            for sub in n.node.subscribes:
                port = n.topic_in.setdefault(sub.topic, n.ports(sub.topic))
                if sub.callback in n.tasks:
                    n.reads[sub.callback].append(port)
                else:
                    self.sink.emit("E705", f"the subscription of node `{n.node.name}` to `{sub.topic}` names callback "
                                   f"`{sub.callback}`, which the node does not have", sub.span, "unknown callback",
                                   help="name one of the node's subscription callbacks")
            for pub in n.node.publishes:
                port = n.topic_out.setdefault(pub.topic, n.ports(pub.topic))
                writers = [c for c in pub.callbacks if c in n.tasks]
                if not writers and len(n.tasks) == 1:  # (CARET: the node's only callback publishes)
                    writers = list(n.tasks)
                if not writers:
                    self.sink.emit("E704", f"which callback of node `{n.node.name}` publishes `{pub.topic}` is not in "
                                   "the architecture file", pub.span, "publisher without callback",
                                   help="add its callback to `callback_names` (CARET: "
                                        "`insert_publisher_callback`), or to the imported task's `produces`")
                for w in writers:
                    n.produces[w].append(port)
            for write, read_, where in n.node.passings:
                if write not in n.tasks or read_ not in n.tasks:
                    self.sink.emit("E705", f"a variable passing of node `{n.node.name}` names a callback the node "
                                   "does not have", where, "unknown callback", help="name two of its callbacks")
                    continue
                out = n.ports(f"{n.tasks[write]}_to_{n.tasks[read_]}")
                into = n.ports(f"{n.tasks[read_]}_from_{n.tasks[write]}")
                n.passing[(write, read_)] = (out, into)
                n.produces[write].append(out)
                n.reads[read_].append(into)
            self._contexts(n)
            if n.tasks:
                self.sink.emit("E704", f"the execution times of node `{n.node.name}`'s callbacks are not in the "
                               "architecture file", n.node.span, "no execution times",
                               help="add `wcet` (and `bcet`) to each task of the imported component, e.g. from "
                                    "CARET's callback durations")

    def _contexts(self, n: _Node) -> None:
        for ctx in n.node.contexts:
            if ctx.kind in ("callback_chain", "UNDEFINED"):
                continue
            if ctx.kind != "use_latest_message":
                self.sink.emit("E703", f"message context `{ctx.kind}` of node `{n.node.name}` has no counterpart: "
                               "its output is related to its input by the callbacks alone", ctx.span,
                               "no counterpart", help="`use_latest_message` and `callback_chain` are modelled")
                continue
            port = n.topic_in.get(ctx.subscription)
            for pub in n.node.publishes:
                if pub.topic != ctx.publisher or port is None:
                    continue
                for cb in pub.callbacks:
                    if cb in n.tasks and port not in n.reads[cb]:
                        n.reads[cb].append(port)

    # ------------------------------------------------------------ executors

    def build_executors(self) -> None:
        groups = {g.name: (n, g) for n in self.nodes.values() for g in n.node.groups}
        names = _Names()
        for ex in self.arch.executors:
            kind = KINDS.get(ex.kind)
            if kind is None:
                self.sink.emit("E703", f"executor `{ex.name}` is a {ex.kind}, which has no counterpart: its callbacks "
                               "are imported without an executor", ex.span, "no counterpart",
                               help="model it as single-threaded executors, or bind its callbacks with priorities "
                                    "and cores")
                continue
            name = names(ex.name)
            self.executors.append((name, kind, ex.name))
            threads = "threads" if kind == "multi_threaded" else "thread"
            self.sink.emit("E704", f"the cores and priority of executor `{ex.name}`'s {threads} are not in the "
                           "architecture file", ex.span, "no core, no priority",
                           help=f"complete `executor {name} {kind}` with `on CORE"
                                f"{', …' if kind == 'multi_threaded' else ''} priority N`")
            if ex.groups and kind != "multi_threaded":
                self.sink.emit("E703", f"the callback groups of executor `{ex.name}` have no counterpart: in a "
                               "single-threaded executor its callbacks run one at a time whatever their group",
                               ex.groups_span, "no counterpart", help="nothing to do: the groups change nothing here")
            for g, where in zip(ex.groups, ex.group_spans or [ex.groups_span] * len(ex.groups), strict=True):
                found = groups.get(g)
                if found is None:
                    self.sink.emit("E702", f"executor `{ex.name}` names callback group `{g}`, which no node has",
                                   where, "unknown group", help="name a group of a node")
                    continue
                n, group = found
                for member in group.callbacks:
                    if member in n.tasks:
                        self.executor_of.setdefault((n.node.name, member), name)
                if kind == "multi_threaded":
                    self._declare_group(n, group)
        for n in self.nodes.values():
            for callback in n.node.callbacks:
                if callback.key in n.tasks and (n.node.name, callback.key) not in self.executor_of:
                    self.sink.emit("E704", f"callback `{callback.name}` of node `{n.node.name}` runs on no executor "
                                   "of the file", callback.span, "no executor",
                                   help="bind the imported task to an executor, or give it a priority and a core")

    def _declare_group(self, n: _Node, group: Group) -> None:
        """A callback group of a multi-threaded executor, declared in its node's instance (§9.4)."""
        if group.kind not in GROUP_KINDS:
            self.sink.emit("E701", f"callback group `{group.name}` has type `{group.kind}`", group.span,
                           "not a callback-group type", help="CARET writes `mutually_exclusive` or `reentrant`")
            return
        local = n.ports(group.name.rsplit("/", 1)[-1] or "group")
        n.groups.append((local, group.kind, group.name))
        for member in group.callbacks:
            if member in n.tasks:
                n.group_of.setdefault(member, local)

    # ------------------------------------------------------------ paths

    def chain(self, path: NamedPath, names: _Names) -> str | None:
        """The chain of a named path (None, after E704, when a step cannot be followed)."""
        refs: list[str] = []
        for k, entry in enumerate(path.entries):
            n = self.nodes.get(entry.node)
            if n is None:
                self.sink.emit("E702", f"path `{path.name}` passes node `{entry.node}`, which the file does not have",
                               entry.span, "unknown node", help="name a node of the file")
                return None
            last = k == len(path.entries) - 1
            steps = self._through(n, entry.subscribe, entry.publish, last)
            if steps is None:
                self.sink.emit("E704", f"path `{path.name}`: no callback of node `{entry.node}` takes "
                               f"`{entry.subscribe or 'its input'}` to `{entry.publish or 'the end'}`", entry.span,
                               "step not followed", help="add the node's variable passings or a message context "
                               "(`use_latest_message`) for it, or the publisher's callbacks")
                return None
            refs += [f"{n.instance}.{s}" for s in steps]
        if not refs:
            return None
        return f"  chain {names(path.name)}: " + " -> ".join(refs)

    def _through(self, n: _Node, sub: str | None, pub: str | None, last: bool) -> list[str] | None:
        """The ports (or, ending a path, the task) a chain follows through node ``n`` from topic ``sub`` to ``pub``."""
        if pub is None:
            if sub is None or sub not in n.topic_in:
                return None
            readers = [cb for cb, ports in n.reads.items() if n.topic_in[sub] in ports]
            return [n.tasks[readers[0]]] if last and readers else None
        out = n.topic_out.get(pub)
        if out is None:
            return None
        writers = [cb for cb, ports in n.produces.items() if out in ports]
        if sub is None:
            return [out] if writers else None
        port = n.topic_in.get(sub)
        if port is None:
            return None
        starts = [cb for cb, ports in n.reads.items() if port in ports]
        for start in starts:  # breadth first over the variable passings, in the file's order
            frontier: list[tuple[str, list[str]]] = [(start, [])]
            seen = {start}
            while frontier:
                cb, via = frontier.pop(0)
                if cb in writers:
                    return via + [out]
                for (w, r), (o, _i) in n.passing.items():
                    if w == cb and r not in seen:
                        seen.add(r)
                        frontier.append((r, via + [o]))
        return None

    # ------------------------------------------------------------ text

    def text(self, system: str) -> str:
        lines = [f"// Imported from the CARET architecture file {comment(self.arch.path)} by `verify import caret`.",
                 "// Execution times, and the cores and priorities of the executors' threads, are not in it.", ""]
        for n in self.nodes.values():
            lines += self._component(n) + [""]
        lines.append(f"system {system} {{")
        lines += [f"  executor {name} {kind}  // {comment(source)}" for name, kind, source in self.executors]
        for n in self.nodes.values():
            lines.append(f"  instance {n.instance} : {n.component} {{")
            lines += [f"    group {name} {kind}  // {comment(source)}" for name, kind, source in n.groups]
            for cb in _distinct(n.node.callbacks):
                if cb.key in n.tasks:
                    lines.append(f"    task {n.tasks[cb.key]}" + self._binding(n, cb))
            lines.append("  }")
        lines += self._connections()
        chains = _Names()
        lines += [c for p in self.arch.paths if (c := self.chain(p, chains)) is not None]
        lines.append("}")
        return "\n".join(lines) + "\n"

    def _component(self, n: _Node) -> list[str]:
        lines = [f"// node {comment(n.node.name)}", f"component {n.component} {{"]
        lines += [f"  in {p} : Message" for p in n.topic_in.values()]
        lines += [f"  out {p} : Message" for p in n.topic_out.values()]
        for (_w, _r), (out, into) in n.passing.items():
            lines += [f"  out {out} : Variable", f"  in {into} : Variable"]
        for cb in _distinct(n.node.callbacks):
            if cb.key not in n.tasks:
                continue
            order = f" (construction_order {cb.order})" if cb.order else ""
            lines.append(f"  task {n.tasks[cb.key]} {{  // {comment(cb.name + order)}")
            lines += [f"    reads {p}" for p in dict.fromkeys(n.reads[cb.key])]
            if n.produces[cb.key]:
                lines.append("    produces " + ", ".join(dict.fromkeys(n.produces[cb.key])))
            lines.append("  }")
        lines.append("}")
        return lines

    def _binding(self, n: _Node, cb: Callback) -> str:
        executor = self.executor_of.get((n.node.name, cb.key))
        text = f" executor {executor}" if executor else ""
        if executor and cb.key in n.group_of:
            text += f" group {n.group_of[cb.key]}"
        if cb.kind == "timer":
            assert cb.period_ns is not None
            return text + f" timer {fmt_time(Fraction(cb.period_ns, 10**9))}"
        port = n.topic_in.get(cb.topic or "")
        return text + (f" trigger {port}" if port is not None else "")

    def _connections(self) -> list[str]:
        lines = []
        publishers: dict[str, list[_Node]] = {}
        for n in self.nodes.values():
            for topic in n.topic_out:
                publishers.setdefault(topic, []).append(n)
        for n in self.nodes.values():
            for sub in n.node.subscribes:
                if sub.topic not in n.topic_in:
                    continue
                writers = publishers.get(sub.topic, [])
                if not writers:
                    self.sink.emit("E704", f"no node of the file publishes `{sub.topic}`, which node `{n.node.name}` "
                                   "subscribes", sub.span, "no publisher", help="bind its callback to a sporadic "
                                   "source (`sporadic A .. B`) with the topic's rates, or import its publisher too")
                    continue
                if len(writers) > 1:
                    self.sink.emit("E703", f"`{sub.topic}` has {len(writers)} publishers; an in-port has one "
                                   f"connection, so `{n.node.name}` is connected from `{writers[0].node.name}` only",
                                   sub.span, "several publishers", help="model each publisher's messages as its own "
                                   "topic, joined by an OR compound port")
                w = writers[0]
                lines.append(f"  connect {w.instance}.{w.topic_out[sub.topic]} -> {n.instance}.{n.topic_in[sub.topic]}")
        for n in self.nodes.values():
            lines += [f"  connect {n.instance}.{out} -> {n.instance}.{into}" for out, into in n.passing.values()]
        return lines


def _distinct(callbacks: list[Callback]) -> list[Callback]:
    """The callbacks of a node, the first of each identity (a later one of the same is reported, E705)."""
    seen: dict[str, Callback] = {}
    for cb in callbacks:
        seen.setdefault(cb.key, cb)
    return list(seen.values())


def import_architecture(arch: Architecture, system: str | None, sink: DiagnosticSink) -> Imported:
    """The architecture as a .vfy text whose system is called ``system`` (default: from the file name)."""
    name = _Names()(system or arch.path.rsplit("/", 1)[-1].rsplit(".", 1)[0])
    importer = _Importer(arch, sink)
    importer.build_nodes()
    importer.build_executors()
    return Imported(importer.text(name), name)


def imported_names(arch: Architecture) -> tuple[dict[str, str], dict[tuple[str, str], str]]:
    """The names the import gives the file's nodes and topics, backwards (the import is deterministic):
    instance -> its node's name, and (instance, out-port) -> the topic it publishes."""
    importer = _Importer(arch, DiagnosticSink())
    importer.build_nodes()
    nodes = {n.instance: name for name, n in importer.nodes.items()}
    topics = {(n.instance, port): topic for n in importer.nodes.values() for topic, port in n.topic_out.items()}
    return nodes, topics
