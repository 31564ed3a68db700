"""SmartMDSD's four model kinds read into plain values (specs/interop.md, "SmartMDSD").

``.component`` (ComponentDefinition), ``.componentArch`` (SystemComponentArchitecture), ``.activityArch``
(ActivityArchitectureModel) and ``.causeEffectChain`` (CuaseEffectChainModel — the toolchain's spelling),
after the Xtext grammars of the SmartMDSD Toolchain V3. What the timing model has no counterpart for is
stepped over and listed in ``Files.dropped`` (reported as E703 by the importer), never silently.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TypedDict

from ...core.diagnostics import DiagnosticSink
from ...core.source import Span
from ..xtext import Cursor, Stop, Tok, tokenize

#: the extensions of the four kinds
KINDS = (".component", ".componentArch", ".activityArch", ".causeEffectChain")
TIME_UNITS = {"sec": Fraction(1), "ms": Fraction(1, 1000), "us": Fraction(1, 1_000_000)}


@dataclass(frozen=True)
class Name:
    text: str
    span: Span


# ------------------------------------------------------------------ .component


@dataclass(frozen=True)
class Port:
    name: Name
    direction: str  # "in", "out"
    service: Name  # the communication service it implements: the message type
    realized_by: Name | None = None  # out-ports: the activity that writes it


@dataclass(frozen=True)
class InputLink:
    port: Name
    optional: bool
    oversampling_ok: bool
    undersampling_ok: bool
    span: Span


@dataclass(frozen=True)
class Constraints:
    configurable: bool
    min_freq: Fraction | None
    max_freq: Fraction | None
    span: Span


@dataclass(frozen=True)
class DefaultTrigger:
    kind: str  # "timer", "input", "observed"
    span: Span
    freq: Fraction | None = None
    port: Name | None = None
    prescale: int = 1


@dataclass(frozen=True)
class Activity:
    name: Name
    handler_of: Name | None = None  # an InputHandler: the in-port whose messages run it
    links: tuple[InputLink, ...] = ()
    constraints: Constraints | None = None
    default: DefaultTrigger | None = None


@dataclass(frozen=True)
class Component:
    name: Name
    ports: tuple[Port, ...]
    activities: tuple[Activity, ...]


# ------------------------------------------------------------------ .componentArch


@dataclass(frozen=True)
class Instance:
    name: Name
    component: Name
    activities: tuple[tuple[Name, Name], ...]  # (component activity, activity node)
    handlers: tuple[tuple[Name, Name], ...]  # (component input handler, input handler node)
    end: Span | None = None  # its closing `}`


@dataclass(frozen=True)
class Connection:
    client: Name  # "Instance.Port" of the RequiredService
    server: Name  # "Instance.Port" of the ProvidedService
    span: Span


@dataclass(frozen=True)
class ComponentArch:
    name: Name
    activity_arch: Name | None
    instances: tuple[Instance, ...]
    connections: tuple[Connection, ...]
    path: str


# ------------------------------------------------------------------ .activityArch


@dataclass(frozen=True)
class Source:
    kind: str  # "timer", "data", "sporadic"
    span: Span
    freq: Fraction | None = None  # timer
    trigger: Name | None = None  # data: the trigger input node
    prescale: int = 1
    min_freq: Fraction | None = None  # sporadic
    max_freq: Fraction | None = None


@dataclass(frozen=True)
class Node:
    name: Name
    handler: bool  # an InputHandlerNode
    inputs: tuple[tuple[Name, str], ...] = ()  # (input node, "register" | "trigger")
    affinity: Name | None = None
    source: Source | None = None
    min_time: Fraction | None = None
    max_time: Fraction | None = None
    time_span: Span | None = None
    scheduler_type: Name | None = None
    priority: tuple[int, Span] | None = None
    prescale: int = 1  # InputHandlerNode


@dataclass(frozen=True)
class Flow:
    source: Name  # a node
    destination: Name  # "Node.Input"
    span: Span


@dataclass(frozen=True)
class ActivityArch:
    name: Name
    cores: tuple[tuple[Name, int], ...]
    nodes: tuple[Node, ...]
    flows: tuple[Flow, ...]
    path: str


# ------------------------------------------------------------------ .causeEffectChain


@dataclass(frozen=True)
class Chain:
    name: Name
    links: tuple[tuple[str, Name], ...]  # ("act" | "hnd", node)
    max_response: tuple[Fraction, Span] | None = None
    min_response: tuple[Fraction, Span] | None = None


@dataclass(frozen=True)
class ChainModel:
    name: Name
    activity_arch: Name
    chains: tuple[Chain, ...]
    path: str


@dataclass
class Files:
    """Everything read from a set of files, with what was stepped over: (what, span)."""

    components: list[Component] = field(default_factory=list)
    component_archs: list[ComponentArch] = field(default_factory=list)
    activity_archs: list[ActivityArch] = field(default_factory=list)
    chain_models: list[ChainModel] = field(default_factory=list)
    dropped: list[tuple[str, Span]] = field(default_factory=list)


def read_text(text: str, path: str, files: Files, sink: DiagnosticSink) -> None:
    """Read one file (its kind from its extension) into ``files``; syntax errors are E701."""
    toks = tokenize(text, path, sink)
    if toks is None:
        return
    kind = next(k for k in KINDS if path.endswith(k))
    cur = Cursor(toks, path, sink, f"a SmartMDSD {kind} file")
    reader = _Reader(cur, files)
    try:
        {".component": reader.component_file, ".componentArch": reader.component_arch,
         ".activityArch": reader.activity_arch, ".causeEffectChain": reader.chain_model}[kind]()
        if cur.peek().kind != "eof":
            raise cur.fail(cur.peek(), "the end of the file")
    except Stop:
        return


def _name(tok: Tok) -> Name:
    return Name(tok.text, tok.span)


class _ActivityFields(TypedDict, total=False):
    """What an activity's body declares besides its links."""

    constraints: Constraints
    default: DefaultTrigger


class _NodeFields(TypedDict, total=False):
    """What an activity node's body declares (``Node``'s optional fields)."""

    affinity: Name
    source: Source
    min_time: Fraction | None
    max_time: Fraction | None
    time_span: Span
    scheduler_type: Name
    priority: tuple[int, Span]


class _Reader:
    def __init__(self, cur: Cursor, files: Files):
        self.cur, self.files = cur, files

    def drop(self, what: str, known: tuple[str, ...]) -> None:
        first, span = self.cur.skip_element(known)
        self.files.dropped.append((f"{what} `{first.text}`" if what else f"`{first.text}`", span))

    def elements(self, handlers: dict[str, Callable[[], object]], known_drops: tuple[str, ...] = ()) -> Tok:
        """``{ element* }``: each element by its keyword; others are dropped (reported)."""
        cur = self.cur
        cur.expect("{")
        keys = tuple(handlers) + known_drops
        while not cur.at("}"):
            tok = cur.peek()
            if tok.kind == "eof":
                raise cur.fail(tok, "`}`")
            handler = handlers.get(tok.text) if tok.kind == "id" else None
            if handler is not None:
                handler()
            else:
                self.drop("", keys)
        return cur.expect("}")

    def freq(self) -> Fraction:
        value, _ = self.cur.decimal("a frequency")
        self.cur.expect("Hz")
        return value

    def time(self) -> tuple[Fraction, Span]:
        value, span = self.cur.integer("a time (an integer)")
        unit = self.cur.ident("a time unit (sec, ms or us)")
        if unit.text not in TIME_UNITS:
            raise self.cur.fail(unit, "a time unit (sec, ms or us)")
        return value * TIME_UNITS[unit.text], span.to(unit.span)

    # -------------------------------------------------------------- .component

    def component_file(self) -> None:
        cur = self.cur
        while cur.at("#import"):
            cur.next()
            cur.fqn()
            cur.accept(".")  # a wildcard import `A.*`
            cur.accept("*")
            cur.semi()
        if cur.peek().kind == "eof":
            return
        cur.expect("ComponentDefinition")
        name = _name(cur.ident())
        if cur.accept("logo"):
            cur.next()
        ports: list[Port] = []
        activities: list[Activity] = []

        def port(direction: str) -> None:
            cur.next()
            pname = _name(cur.ident())
            cur.expect("implements")
            service = _name(cur.fqn("a service"))
            realized = None
            if direction == "out":
                cur.expect("realizedBy")
                realized = _name(cur.fqn("an activity"))
            self.elements({})  # its extensions (SupportedMiddleware): reported, none has a counterpart
            ports.append(Port(pname, direction, service, realized))

        def activity() -> None:
            cur.next()
            activities.append(self.activity(_name(cur.ident()), None))

        def handler() -> None:
            cur.next()
            hname = _name(cur.ident())
            cur.expect("triggeredFrom")
            port_name = _name(cur.fqn("an in-port"))
            if (queue := cur.accept("activeQueue")) is not None:
                self.files.dropped.append(("`activeQueue` of an input handler", queue.span))
            activities.append(self.activity(hname, port_name))

        self.elements({"InputPort": lambda: port("in"), "OutputPort": lambda: port("out"),
                       "Activity": activity, "InputHandler": handler})
        self.files.components.append(Component(name, tuple(ports), tuple(activities)))

    def activity(self, name: Name, handler_of: Name | None) -> Activity:
        cur = self.cur
        links: list[InputLink] = []
        found: _ActivityFields = {}

        def link() -> None:
            start = cur.next()
            port = _name(cur.fqn("an in-port"))
            cur.expect("{")
            flags = set()
            while not cur.at("}"):
                flag = cur.ident("optional, oversamplingOk or undersamplingOk")
                if flag.text not in ("optional", "oversamplingOk", "undersamplingOk"):
                    raise cur.fail(flag, "optional, oversamplingOk or undersamplingOk")
                flags.add(flag.text)
            end = cur.expect("}")
            links.append(InputLink(port, "optional" in flags, "oversamplingOk" in flags, "undersamplingOk" in flags,
                                   start.span.to(end.span)))

        def constraints() -> None:
            start = cur.next()
            cur.expect("{")
            cur.expect("configurable")
            cur.expect("=")
            flag = cur.ident("true or false")
            if flag.text not in ("true", "false"):
                raise cur.fail(flag, "true or false")
            cur.semi()
            bounds: dict[str, Fraction] = {}
            while cur.at("minActFreq", "maxActFreq"):
                key = cur.next().text
                cur.expect("=")
                bounds[key] = self.freq()
                cur.semi()
            end = cur.expect("}")
            found["constraints"] = Constraints(flag.text == "true", bounds.get("minActFreq"),
                                               bounds.get("maxActFreq"), start.span.to(end.span))

        def default() -> None:
            start = cur.next()
            if cur.accept("PeriodicTimer"):
                value, span = cur.decimal("a frequency")
                end = cur.expect("Hz")
                found["default"] = DefaultTrigger("timer", start.span.to(end.span), freq=value)
            elif cur.accept("InputPortTrigger"):
                port = _name(cur.fqn("an in-port"))
                prescale, span = 1, port.span
                if cur.accept("prescale"):
                    prescale, span = cur.integer("a prescaler")
                found["default"] = DefaultTrigger("input", start.span.to(span), port=port, prescale=prescale)
            elif cur.accept("ObservedElement"):
                element = _name(cur.fqn("an activity or handler"))
                found["default"] = DefaultTrigger("observed", start.span.to(element.span), port=element)
            else:
                raise cur.fail(cur.peek(), "PeriodicTimer, InputPortTrigger or ObservedElement")
            cur.semi()

        self.elements({"InputPortLink": link, "ActivationConstraints": constraints, "DefaultTrigger": default},
                      ("Observe", "RequestPortLink", "OperationModeBinding", "OpcUaClientLink", "MixedPortROSLink"))
        return Activity(name, handler_of, tuple(links), found.get("constraints"), found.get("default"))

    # -------------------------------------------------------------- .componentArch

    def component_arch(self) -> None:
        cur = self.cur
        cur.expect("SystemComponentArchitecture")
        name = _name(cur.ident())
        arch = None
        if cur.accept("usingActivityArchitecture"):
            arch = _name(cur.fqn())
        instances: list[Instance] = []
        connections: list[Connection] = []

        def instance() -> None:
            cur.next()
            iname = _name(cur.ident())
            cur.expect("instantiates")
            comp = _name(cur.fqn("a component"))
            acts: list[tuple[Name, Name]] = []
            hnds: list[tuple[Name, Name]] = []

            def service() -> None:  # the ports in use: the connections say all the timing needs
                cur.next()
                cur.fqn("a port")
                cur.semi()

            def mapping(into: list[tuple[Name, Name]]) -> None:
                cur.next()
                sub = _name(cur.fqn())
                cur.expect("configuration")
                into.append((sub, _name(cur.fqn("an activity architecture node"))))
                cur.semi()

            end = self.elements({"RequiredService": service, "ProvidedService": service,
                                 "Activity": lambda: mapping(acts), "InputHandler": lambda: mapping(hnds)},
                                ("ParameterStructInstance", "OpcUaDeviceClientInstance", "OpcUaReadServerInstance"))
            instances.append(Instance(iname, comp, tuple(acts), tuple(hnds), end.span))

        def connection() -> None:
            start = cur.next()
            client = _name(cur.fqn("a required service"))
            cur.expect("->")
            server = _name(cur.fqn("a provided service"))
            end = server.span
            if cur.at("useMiddleware"):
                first, span = cur.skip_element(("Connection", "ComponentInstance", "CoordinationModuleMapping",
                                                "BehaviorTaskRef"))
                self.files.dropped.append(("the middleware choice `useMiddleware` of a connection", span))
            cur.semi()
            connections.append(Connection(client, server, start.span.to(end)))

        self.elements({"ComponentInstance": instance, "Connection": connection},
                      ("CoordinationModuleMapping", "BehaviorTaskRef"))
        self.files.component_archs.append(ComponentArch(name, arch, tuple(instances), tuple(connections), cur.path))

    # -------------------------------------------------------------- .activityArch

    def activity_arch(self) -> None:
        cur = self.cur
        cur.expect("ActivityArchitectureModel")
        name = _name(cur.ident())
        cores: list[tuple[Name, int]] = []
        nodes: list[Node] = []
        flows: list[Flow] = []

        def core() -> None:
            cur.next()
            cname = _name(cur.ident())
            cur.expect("{")
            cur.expect("coreNumber")
            number, _ = cur.integer("a core number")
            cur.semi()
            cur.expect("}")
            cores.append((cname, number))

        def handler_node() -> None:
            cur.next()
            hname = _name(cur.ident())
            cur.expect("{")
            inputs: list[tuple[Name, str]] = []
            prescale = 1
            if cur.accept("input"):
                cur.expect("TriggerInputNode")
                inputs.append((_name(cur.ident()), "trigger"))
                cur.semi()
            if cur.accept("prescale"):
                prescale, _ = cur.integer("a prescaler")
            cur.expect("}")
            nodes.append(Node(hname, True, tuple(inputs), prescale=prescale))

        def flow() -> None:
            start = cur.next()
            cur.expect("{")
            cur.expect("source")
            source = _name(cur.fqn("a node"))
            cur.expect("destination")
            dest = _name(cur.fqn("an input node"))
            end = cur.expect("}")
            flows.append(Flow(source, dest, start.span.to(end.span)))

        self.elements({"CPUCore": core, "InputHandlerNode": handler_node,
                       "ActivityNode": lambda: nodes.append(self.activity_node()), "DataFlow": flow})
        self.files.activity_archs.append(ActivityArch(name, tuple(cores), tuple(nodes), tuple(flows), cur.path))

    def activity_node(self) -> Node:
        cur = self.cur
        cur.next()
        name = _name(cur.ident())
        cur.expect("{")
        inputs: list[tuple[Name, str]] = []
        fields: _NodeFields = {}
        if cur.accept("inputs"):
            cur.expect("{")
            while cur.at("RegisterInputNode", "TriggerInputNode"):
                kind = "register" if cur.next().text == "RegisterInputNode" else "trigger"
                inputs.append((_name(cur.ident()), kind))
                cur.semi()
            cur.expect("}")
        while not cur.at("}"):
            key = cur.ident("cpuAffinity, activationSource, executionTime, scheduler or `}`")
            if key.text == "cpuAffinity":
                fields["affinity"] = _name(cur.fqn("a CPU core"))
                cur.semi()
            elif key.text == "activationSource":
                fields["source"] = self.source()
            elif key.text == "executionTime":
                cur.expect("{")
                times: dict[str, Fraction] = {}
                while cur.at("minTime", "maxTime"):
                    which = cur.next().text
                    times[which], _ = self.time()
                    cur.semi()
                end = cur.expect("}")
                fields["min_time"], fields["max_time"] = times.get("minTime"), times.get("maxTime")
                fields["time_span"] = key.span.to(end.span)
            elif key.text == "scheduler":
                cur.expect("{")
                while cur.at("type", "priority"):
                    if cur.next().text == "type":
                        fields["scheduler_type"] = _name(cur.ident("DEFAULT, FIFO or RR"))
                    else:
                        fields["priority"] = cur.integer("a priority")
                    cur.semi()
                cur.expect("}")
            else:
                raise cur.fail(key, "cpuAffinity, activationSource, executionTime, scheduler or `}`")
        cur.expect("}")
        return Node(name, False, tuple(inputs), **fields)

    def source(self) -> Source:
        cur = self.cur
        kind = cur.ident("PeriodicTimer, DataTriggered or Sporadic")
        if kind.text == "PeriodicTimer":
            cur.expect("{")
            cur.expect("periodicActFreq")
            freq = self.freq()
            cur.semi()
            end = cur.expect("}")
            return Source("timer", kind.span.to(end.span), freq=freq)
        if kind.text == "DataTriggered":
            trigger = _name(cur.fqn("a trigger input node"))
            cur.expect("{")
            cur.expect("prescale")
            prescale, _ = cur.integer("a prescaler")
            cur.semi()
            end = cur.expect("}")
            return Source("data", kind.span.to(end.span), trigger=trigger, prescale=prescale)
        if kind.text == "Sporadic":
            cur.expect("{")
            bounds: dict[str, Fraction] = {}
            while cur.at("minActFreq", "maxActFreq"):
                key = cur.next().text
                bounds[key] = self.freq()
                cur.semi()
            end = cur.expect("}")
            return Source("sporadic", kind.span.to(end.span), min_freq=bounds.get("minActFreq"),
                          max_freq=bounds.get("maxActFreq"))
        raise cur.fail(kind, "PeriodicTimer, DataTriggered or Sporadic")

    # -------------------------------------------------------------- .causeEffectChain

    def chain_model(self) -> None:
        cur = self.cur
        cur.expect("CuaseEffectChainModel")
        name = _name(cur.ident())
        cur.expect("refinesActivityArch")
        arch = _name(cur.fqn())
        chains: list[Chain] = []

        def chain() -> None:
            cur.next()
            cname = _name(cur.ident())
            cur.expect("{")
            links: list[tuple[str, Name]] = []
            fields: dict[str, tuple[Fraction, Span]] = {}
            if cur.accept("chainLinks"):
                cur.expect("{")
                while True:
                    kind = cur.ident("act. or hnd.")
                    if kind.text not in ("act", "hnd"):
                        raise cur.fail(kind, "act. or hnd.")
                    cur.expect(".")
                    links.append((kind.text, _name(cur.fqn("a node"))))
                    if not cur.accept("->"):
                        break
                cur.expect("}")
            while cur.at("desiredMinResponse", "desiredMaxResponse"):
                key = cur.next()
                value, span = self.time()
                fields[key.text] = (value, key.span.to(span))
                cur.semi()
            cur.expect("}")
            chains.append(Chain(cname, tuple(links), fields.get("desiredMaxResponse"),
                                fields.get("desiredMinResponse")))

        self.elements({"ActivityChain": chain})
        self.files.chain_models.append(ChainModel(name, arch, tuple(chains), cur.path))
