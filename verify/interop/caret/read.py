"""Reading a CARET architecture file (``architecture.yaml`` of tier4/caret_analyze) with every value located.

The file is YAML (PyYAML's safe composer: no tags, no code); the reader keeps each value's position,
so that every diagnostic points at the line it is about. The format is the one ``caret_analyze``
reads with ``Architecture('yaml', path)`` and writes with ``Architecture.export``: top-level
``named_paths``, ``executors`` and ``nodes`` (specs/interop.md, "CARET"). ``UNDEFINED`` (and, for a
path's topics, null) means "not set", as in CARET. Malformed files are E701 (not YAML, or not of that
shape), inconsistent ones E705 (a name defined twice, a reference to a callback of no node).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import yaml

from ...core.diagnostics import DiagnosticSink
from ...core.limits import DEFAULT_LIMITS, Limits
from ...core.source import Span

UNDEFINED = "UNDEFINED"
#: the most characters of a number (the language's own limit, ``verify.core.limits``: E005)
NUMBER_LENGTH = DEFAULT_LIMITS.number_length
#: topics CARET leaves out of every architecture
IGNORED_TOPICS = ("/parameter_events", "/rosout", "/clock")


class Malformed(Exception):
    """The file is not an architecture file: E701 at ``span``."""

    def __init__(self, message: str, span: Span, help: str, code: str = "E701"):
        super().__init__(message)
        self.span, self.help, self.code = span, help, code


@dataclass(frozen=True)
class Y:
    """A YAML value with its position: ``value`` is a str, None, a list of Y or a dict of str to Y."""

    value: object
    span: Span


def _span(path: str, node: yaml.Node) -> Span:
    start, end = node.start_mark, node.end_mark
    return Span(path, start.line + 1, start.column + 1, end.line + 1, max(end.column, 1) + (start.line == end.line))


def parse(text: str, path: str, limits: Limits) -> Y:
    """The document as located values (Malformed when it is not YAML, holds anchors, or is too big)."""
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
        raise Malformed(f"not YAML: {err.problem or err}", Span(path, line, col, line, col + 1),
                        "an architecture file is YAML, as `Architecture.export` writes it") from None
    except yaml.YAMLError as err:
        raise Malformed(f"not YAML: {err}", Span(path, 1, 1, 1, 2), "an architecture file is YAML") from None
    if root is None:
        raise Malformed("the file is empty", Span(path, 1, 1, 1, 2),
                        "an architecture file holds `named_paths`, `executors` and `nodes`")
    budget = [limits.tokens]
    return _convert(root, path, budget, set())


def _convert(node: yaml.Node, path: str, budget: list[int], seen: set[int]) -> Y:
    budget[0] -= 1
    if budget[0] < 0:
        raise Malformed("the file has more values than the limit of one run", _span(path, node),
                        "import the architecture of one system")
    if id(node) in seen:  # an alias: CARET never writes one, and a chain of them explodes
        raise Malformed("this value (`&name`) is repeated by an alias (`*name`)", _span(path, node),
                        "write the value out: architecture files have no anchors or aliases")
    seen.add(id(node))
    if isinstance(node, yaml.ScalarNode):
        value = None if node.tag == "tag:yaml.org,2002:null" else str(node.value)
        return Y(value, _span(path, node))
    if isinstance(node, yaml.SequenceNode):
        return Y([_convert(item, path, budget, seen) for item in node.value], _span(path, node))
    assert isinstance(node, yaml.MappingNode)
    out: dict[str, Y] = {}
    for key, value in node.value:
        if not isinstance(key, yaml.ScalarNode):
            raise Malformed("a key that is not a name", _span(path, key), "keys are plain names such as `nodes`")
        out.setdefault(str(key.value), _convert(value, path, budget, seen))
    return Y(out, _span(path, node))


# ------------------------------------------------------------------ the architecture


@dataclass
class Callback:
    name: str
    kind: str  # "timer" | "subscription"
    span: Span
    period_ns: int | None = None
    topic: str | None = None
    symbol: str | None = None
    order: int = 0  # `construction_order`: tells apart callbacks alike in name, type, period or topic and symbol

    @property
    def key(self) -> str:
        """The callback's identity in its node: its name, and its construction order unless 0 (CARET: a
        reference by name alone means construction order 0)."""
        return self.name if self.order == 0 else f"{self.name}#{self.order}"


@dataclass
class Publish:
    topic: str
    callbacks: list[str]
    span: Span


@dataclass
class Subscribe:
    topic: str
    callback: str
    span: Span


@dataclass
class Context:
    kind: str
    subscription: str
    publisher: str
    span: Span


@dataclass
class Group:
    name: str
    kind: str
    callbacks: list[str]
    span: Span


@dataclass
class Node:
    name: str
    span: Span
    callbacks: list[Callback] = field(default_factory=list)
    groups: list[Group] = field(default_factory=list)
    passings: list[tuple[str, str, Span]] = field(default_factory=list)  # (write, read, where)
    publishes: list[Publish] = field(default_factory=list)
    subscribes: list[Subscribe] = field(default_factory=list)
    contexts: list[Context] = field(default_factory=list)

    def callback(self, name: str) -> Callback | None:
        return next((c for c in self.callbacks if c.name == name), None)


@dataclass
class Executor:
    name: str
    kind: str
    groups: list[str]
    span: Span
    groups_span: Span
    group_spans: list[Span] = field(default_factory=list)  # each group name where it stands


@dataclass
class PathEntry:
    node: str
    publish: str | None
    subscribe: str | None
    span: Span


@dataclass
class NamedPath:
    name: str
    entries: list[PathEntry]
    span: Span


@dataclass
class Architecture:
    nodes: list[Node]
    executors: list[Executor]
    paths: list[NamedPath]
    path: str

    def node(self, name: str) -> Node | None:
        return next((n for n in self.nodes if n.name == name), None)


def _map(y: Y, what: str) -> dict[str, Y]:
    if not isinstance(y.value, dict):
        raise Malformed(f"{what} is not a mapping of keys", y.span, f"write {what} as `key: value` lines")
    return y.value


def _list(y: Y, what: str) -> list[Y]:
    if not isinstance(y.value, list):
        raise Malformed(f"{what} is not a list", y.span, f"write {what} as a list (`- …` lines, or `[]`)")
    return y.value


def _key(m: Y, key: str, what: str) -> Y:
    found = _map(m, what).get(key)
    if found is None or found.value is None:
        raise Malformed(f"{what} has no `{key}`", m.span, f"add `{key}:` (CARET requires it)")
    return found


def _text(y: Y, what: str) -> str:
    if not isinstance(y.value, str):
        raise Malformed(f"{what} is not a name or a number", y.span, f"write {what} as a plain value")
    return y.value


def _optional_list(m: Y, key: str, what: str) -> list[Y]:
    found = _map(m, what).get(key)
    return [] if found is None or found.value is None else _list(found, f"`{key}` of {what}")


def _topic(m: Y, key: str) -> str | None:
    found = _map(m, "a path entry").get(key)
    if found is None or found.value is None or found.value == UNDEFINED:
        return None
    return _text(found, f"`{key}`")


def read_architecture(root: Y, path: str) -> Architecture:
    """The architecture of a parsed file (Malformed on a shape CARET would not read)."""
    if _is_early(root):
        nodes = [_node(y) for y in _list(_key(root, "nodes", "the file"), "`nodes`")]
        for node in nodes:  # (its subscriptions are those of its subscription callbacks)
            node.subscribes += [Subscribe(c.topic, c.name, c.span) for c in node.callbacks
                                if c.topic is not None and c.topic not in IGNORED_TOPICS]
        paths = [_path(y) for y in _optional_list(root, "named_paths", "the architecture file")]
        return Architecture([n for n in nodes if "caret_trace_" not in n.name], [], paths, path)
    for key in ("named_paths", "executors", "nodes"):
        _list(_key(root, key, "the architecture file"), f"`{key}`")
    nodes = [_node(y) for y in _list(_key(root, "nodes", "the file"), "`nodes`")]
    executors = [_executor(y) for y in _list(_key(root, "executors", "the file"), "`executors`")]
    paths = [_path(y) for y in _list(_key(root, "named_paths", "the file"), "`named_paths`")]
    return Architecture([n for n in nodes if "caret_trace_" not in n.name], executors, paths, path)


def _is_early(root: Y) -> bool:
    """A file of CARET's early format (before named paths and executors were recorded, 2021): top-level
    ``path_name_aliases`` instead of ``named_paths``, no ``executors``; a callback's ``type``, a
    publisher's one ``callback_name``, no ``subscribes`` (a subscription callback's topic is the node's
    subscription). Its aliases name no path; ``named_paths`` are those ``export caret --from`` added."""
    keys = _map(root, "the architecture file")
    return "path_name_aliases" in keys and "executors" not in keys


def _node(y: Y) -> Node:
    name = _text(_key(y, "node_name", "a node"), "`node_name`")
    node = Node(name, _key(y, "node_name", "a node").span)
    what = f"node `{name}`"
    for c in _optional_list(y, "callbacks", what):
        node.callbacks.append(_callback(c, what))
    for g in _optional_list(y, "callback_groups", what):
        names = [_text(n, "a callback name") for n in _list(_key(g, "callback_names", "a callback group"),
                                                              "`callback_names`")]
        node.groups.append(Group(_text(_key(g, "callback_group_name", "a callback group"), "the group's name"),
                                 _text(_key(g, "callback_group_type", "a callback group"), "the group's type"),
                                 names, g.span))
    for v in _optional_list(y, "variable_passings", what):
        write = _text(_key(v, "callback_name_write", "a variable passing"), "`callback_name_write`")
        read = _text(_key(v, "callback_name_read", "a variable passing"), "`callback_name_read`")
        if UNDEFINED not in (write, read):
            node.passings.append((write, read, v.span))
    for p in _optional_list(y, "publishes", what):
        callbacks = _publishers(p)
        topic = _text(_key(p, "topic_name", "a publisher"), "`topic_name`")
        if topic not in IGNORED_TOPICS:
            node.publishes.append(Publish(topic, [c for c in callbacks if c != UNDEFINED], p.span))
    for s in _optional_list(y, "subscribes", what):
        topic = _text(_key(s, "topic_name", "a subscription"), "`topic_name`")
        if topic not in IGNORED_TOPICS:
            node.subscribes.append(Subscribe(topic, _text(_key(s, "callback_name", "a subscription"),
                                                          "`callback_name`"), s.span))
    for m in _optional_list(y, "message_contexts", what):
        node.contexts.append(Context(_text(_key(m, "context_type", "a message context"), "`context_type`"),
                                     _text(_key(m, "subscription_topic_name", "a message context"), "a topic"),
                                     _text(_key(m, "publisher_topic_name", "a message context"), "a topic"),
                                     m.span))
    return node


def _publishers(p: Y) -> list[str]:
    """The callbacks a publisher names: ``callback_names``, or the early format's one ``callback_name``."""
    fields = _map(p, "a publisher")
    if "callback_names" not in fields and "callback_name" in fields:
        return [_text(fields["callback_name"], "`callback_name`")]
    return [_text(c, "a callback name") for c in _list(_key(p, "callback_names", "a publisher"), "`callback_names`")]


def _callback(c: Y, what: str) -> Callback:
    fields = _map(c, f"a callback of {what}")
    kind_y = fields.get("callback_type") or fields.get("type")  # (`type`: the format before CARET 1.0)
    if kind_y is None or kind_y.value is None:
        raise Malformed(f"a callback of {what} has no `callback_type`", c.span,
                        "add `callback_type: timer_callback` or `subscription_callback`")
    name = _text(_key(c, "callback_name", f"a callback of {what}"), "`callback_name`")
    kind = _text(kind_y, "`callback_type`")
    symbol = fields["symbol"].value if "symbol" in fields and isinstance(fields["symbol"].value, str) else None
    order = _construction_order(fields, name)
    if kind == "timer_callback":
        period = _text(_key(c, "period_ns", f"timer callback `{name}`"), "`period_ns`")
        if len(period) > NUMBER_LENGTH:  # (never converted whole: no number is longer in the language either)
            raise Malformed(f"the period of timer callback `{name}` has {len(period):,} characters; at most "
                            f"{NUMBER_LENGTH} are allowed", fields["period_ns"].span,
                            "write `period_ns` as a whole number of nanoseconds, e.g. 100000000", "E005")
        if not period.isascii() or not period.isdigit() or int(period) <= 0:
            raise Malformed(f"the period of timer callback `{name}` is not a positive number of nanoseconds",
                            fields["period_ns"].span, "write `period_ns` as a whole number, e.g. 100000000")
        return Callback(name, "timer", c.span, period_ns=int(period), symbol=symbol, order=order)
    if kind == "subscription_callback":
        topic = _text(_key(c, "topic_name", f"subscription callback `{name}`"), "`topic_name`")
        return Callback(name, "subscription", c.span, topic=topic, symbol=symbol, order=order)
    return Callback(name, kind, c.span, symbol=symbol, order=order)


def _construction_order(fields: dict[str, Y], name: str) -> int:
    """A callback's ``construction_order`` (CARET: 0 when absent)."""
    found = fields.get("construction_order")
    if found is None or found.value is None:
        return 0
    text = _text(found, "`construction_order`")
    if not text.isascii() or not text.isdigit() or len(text) > NUMBER_LENGTH:
        raise Malformed(f"the construction order of callback `{name}` is not a whole number", found.span,
                        "write `construction_order` as 0, 1, 2 … (the callback's rank among those alike)")
    return int(text)


def _executor(y: Y) -> Executor:
    names = _key(y, "callback_group_names", "an executor")
    items = _list(names, "`callback_group_names`")
    return Executor(_text(_key(y, "executor_name", "an executor"), "`executor_name`"),
                    _text(_key(y, "executor_type", "an executor"), "`executor_type`"),
                    [_text(n, "a callback group name") for n in items], y.span, names.span, [n.span for n in items])


def _path(y: Y) -> NamedPath:
    entries = [PathEntry(_text(_key(e, "node_name", "a path entry"), "`node_name`"),
                         _topic(e, "publish_topic_name"), _topic(e, "subscribe_topic_name"), e.span)
               for e in _list(_key(y, "node_chain", "a named path"), "`node_chain`")]
    return NamedPath(_text(_key(y, "path_name", "a named path"), "`path_name`"), entries, y.span)


def read(text: str, path: str, sink: DiagnosticSink, limits: Limits) -> Architecture | None:
    """The architecture in ``text``, or None after E701."""
    try:
        return read_architecture(parse(text, path, limits), path)
    except Malformed as err:
        sink.emit(err.code, f"{path} is not a CARET architecture file: {err}", err.span, "here", help=err.help)
    except RecursionError:
        sink.emit("E701", f"{path} is nested too deeply", Span(path, 1, 1, 1, 2), "too deep",
                  help="an architecture file nests four levels")
    return None
