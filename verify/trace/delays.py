"""Connection delays measured from the messages of a trace (specs/trace.md §3, §4): each link of the
recording (topic, publishing node, subscribing node: ``recording.Link``) paired with the model's
connection between the nodes' instances, its delays (publish → receipt) against the connection's
``delay`` range, and E807 where a message took longer than the range's maximum, or less than its
minimum.

A link is paired with the connection from an out-port of the publishing node's instance to an in-port
of the subscribing node's instance (instances named as ``verify import caret`` names nodes); when there
are several, with the one whose out-port or in-port is named after the topic's last part. What cannot
be paired is listed, never guessed.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from ..core.diagnostics import DiagnosticSink, Severity
from ..frontend.loader import Project
from ..interop.caret.to_vfy import language_name
from ..model import syntax as s
from ..model.system import LinkModel, SystemModel
from ..model.units import fmt_time
from .metrics import Distribution
from .recording import Link, Recording


@dataclass(frozen=True)
class ConnectionMeasure:
    """The measured delays of a connection of the model (seconds), and its modelled range."""

    source: str  # out-port id, "inst.port"
    target: str  # in-port id
    topics: tuple[str, ...]
    delays: Distribution
    delay_min: Fraction
    delay_max: Fraction

    @property
    def connection(self) -> str:
        return f"{self.source} -> {self.target}"


@dataclass(frozen=True)
class Delays:
    connections: tuple[ConnectionMeasure, ...]
    unpaired: tuple[tuple[str, str], ...]  # (the link in words, why it is not paired)

    def of(self, source: str, target: str) -> ConnectionMeasure | None:
        return next((c for c in self.connections if c.source == source and c.target == target), None)


def describe(link: Link) -> str:
    return f"`{link.topic}` from node `{link.publisher}` to node `{link.subscriber}` ({len(link.delays)} messages)"


def _instance(port: str) -> str:
    return port.split(".", 1)[0]


def pair(model: SystemModel, link: Link) -> LinkModel | str:
    """The connection ``link`` measures, or why there is none."""
    writer, reader = language_name(link.publisher), language_name(link.subscriber)
    between = [lk for lk in model.links if _instance(lk.source) == writer and _instance(lk.target) == reader]
    if len(between) > 1:
        named = language_name(link.topic.rstrip("/").rsplit("/", 1)[-1])
        between = [lk for lk in between if named in (lk.source.split(".", 1)[1], lk.target.split(".", 1)[1])]
    if len(between) == 1:
        return between[0]
    if between:
        return f"{len(between)} connections from `{writer}` to `{reader}`, none named after the topic: not told apart"
    return f"the model has no connection from an instance `{writer}` to an instance `{reader}`"


def measure_delays(model: SystemModel, recording: Recording) -> Delays:
    """The delays of every connection of ``model`` that ``recording`` has messages of."""
    found: dict[tuple[str, str], tuple[LinkModel, list[str], list[int]]] = {}
    unpaired = []
    for link in recording.links.values():
        connection = pair(model, link)
        if isinstance(connection, str):
            unpaired.append((describe(link), connection))
            continue
        _, topics, values = found.setdefault((connection.source, connection.target), (connection, [], []))
        topics.append(link.topic)
        values.extend(link.delays)
    measures = []
    for connection, topics, values in found.values():
        d = Distribution.of(values)
        if d is not None:
            measures.append(ConnectionMeasure(connection.source, connection.target, tuple(dict.fromkeys(topics)), d,
                                              connection.delay_min, connection.delay_max))
    order = {(str(lk.source), str(lk.target)): k for k, lk in enumerate(model.links)}
    measures.sort(key=lambda c: order[(c.source, c.target)])
    return Delays(tuple(measures), tuple(unpaired))


def connection_syntax(project: Project, system: str, source: str, target: str) -> s.Connection | None:
    """The ``connect`` statement of ``system`` from ``source`` to ``target`` (port ids)."""
    for module in project.modules:
        for sy in module.systems:
            if sy.name.text == system:
                return next((c for c in sy.connections if str(c.source) == source and str(c.target) == target), None)
    return None


def delay_findings(model: SystemModel, delays: Delays, project: Project, sink: DiagnosticSink) -> None:
    """E807 for every connection a message of which took longer than its modelled maximum, or less than
    its minimum."""
    for c in delays.connections:
        if c.delays.max > c.delay_max:
            said = (f"above its delay's maximum {fmt_time(c.delay_max)}" if c.delay_max
                    else "above the zero delay the model takes for a connection without `delay`")
            _delay_finding(model, project, c, f"a message took {fmt_time(c.delays.max)} from its publish to its "
                           f"receipt in the trace, {said}: the bounds assume no message takes longer",
                           "a receipt is when the subscriber's executor took the message: the time it waited "
                           "there while the executor ran other callbacks counts too", sink)
        if c.delays.min < c.delay_min:
            _delay_finding(model, project, c, f"a message took only {fmt_time(c.delays.min)} from its publish to "
                           f"its receipt in the trace, below its delay's minimum {fmt_time(c.delay_min)}: the bounds "
                           "assume no message is faster", "a receipt is at or after the message became readable: "
                           "the message was at least this fast", sink)


def _delay_finding(model: SystemModel, project: Project, c: ConnectionMeasure, message: str, why: str,
                   sink: DiagnosticSink) -> None:
    syntax = connection_syntax(project, model.name, c.source, c.target)
    span = next((lk.span for lk in model.links if (lk.source, lk.target) == (c.source, c.target)), model.span)
    if syntax is not None and syntax.delay_max is not None and syntax.delay_min is not None:
        span = syntax.delay_min.span.to(syntax.delay_max.span)
    sink.emit("E807", f"connection `{c.connection}`: {message}", span, "measured outside this",
              severity=Severity.WARNING,
              notes=[f"measured over {c.delays.count} messages of {', '.join(c.topics)}: min {fmt_time(c.delays.min)}, "
                     f"p50 {fmt_time(c.delays.p50)}, p99 {fmt_time(c.delays.p99)}, max {fmt_time(c.delays.max)}", why],
              help="give the connection a delay that covers the measured one (`verify trace --calibrate` "
                   "writes it), or find what holds its messages up")
