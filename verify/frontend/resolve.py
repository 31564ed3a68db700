"""Name resolution: its own pass, which reports *every* unknown or duplicate name, with "did you mean".

Builds scopes (what each name refers to) for components and systems. Later passes use the scopes and
run only on systems whose names all resolved.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from collections.abc import Callable, Iterable
from typing import Literal, TypeVar

from ..model import syntax as s
from ..core.diagnostics import DiagnosticSink, Label, suggest
from .loader import Project

MemberKind = Literal["in-port", "out-port", "compound in-port", "task"]
#: what a member name of a component declares
MemberNode = s.InPort | s.OutPort | s.CompoundPort | s.Task
_Node = TypeVar("_Node")
KNOWN_POLICIES = ("fixed_priority",)
#: the executor kinds of specs/timing.md §9 (rclcpp's SingleThreadedExecutor, StaticSingleThreadedExecutor,
#: EventsExecutor and MultiThreadedExecutor)
KNOWN_EXECUTORS = ("single_threaded", "static_single_threaded", "events", "multi_threaded")
#: the callback-group kinds of specs/timing.md §9.4 (rclcpp's CallbackGroupType)
KNOWN_GROUPS = ("mutually_exclusive", "reentrant")


@dataclass(frozen=True)
class ComponentScope:
    component: s.Component
    members: dict[str, tuple[MemberKind, MemberNode]] = field(compare=False)

    @property
    def name(self) -> str:
        return self.component.name.text

    def kind_of(self, name: str) -> MemberKind | None:
        entry = self.members.get(name)
        return entry[0] if entry else None

    def get(self, name: str) -> MemberNode | None:
        entry = self.members.get(name)
        return entry[1] if entry else None

    def names(self, *kinds: MemberKind) -> list[str]:
        return [n for n, (k, _) in self.members.items() if not kinds or k in kinds]


@dataclass(frozen=True)
class SystemScope:
    system: s.System
    cores: dict[str, s.Core] = field(compare=False)
    instances: dict[str, s.Instance] = field(compare=False)
    component_of: dict[str, ComponentScope] = field(compare=False)  # instance name -> scope
    bindings: dict[tuple[str, str], s.TaskBinding] = field(compare=False)
    resolved: bool = True
    executors: dict[str, s.Executor] = field(default_factory=dict, compare=False)
    #: the project's message declarations: message type -> its ROS message
    messages: dict[str, s.Message] = field(default_factory=dict, compare=False)

    @property
    def name(self) -> str:
        return self.system.name.text


@dataclass(frozen=True)
class Resolution:
    components: dict[str, ComponentScope] = field(compare=False)
    systems: dict[str, SystemScope] = field(compare=False)
    messages: dict[str, s.Message] = field(default_factory=dict, compare=False)


def _unknown(sink: DiagnosticSink, what: str, name: s.Name, candidates: Iterable[str], where: str = "") -> None:
    hint = suggest(name.text, candidates)
    help = f"did you mean `{hint}`?" if hint else f"declare {what} `{name.text}`{where}, or check the spelling"
    sink.emit("E101", f"unknown {what} `{name.text}`{where}", name.span, f"no {what} of this name", help=help)


def _duplicate(sink: DiagnosticSink, what: str, name: s.Name, first: s.Name, *, message: str | None = None,
               help: str = "rename or remove one of the two") -> None:
    sink.emit("E102", message or f"{what} `{name.text}` is declared more than once", name.span,
              "declared again here", secondary=(Label(first.span, "first declared here"),), help=help)


def _scope_component(comp: s.Component, sink: DiagnosticSink) -> ComponentScope:
    members: dict[str, tuple[MemberKind, MemberNode]] = {}
    first: dict[str, s.Name] = {}
    entries: list[tuple[MemberKind, s.Name, MemberNode]] = (
        [("in-port", p.name, p) for p in comp.in_ports]
        + [("out-port", p.name, p) for p in comp.out_ports]
        + [("compound in-port", p.name, p) for p in comp.compounds]
        + [("task", t.name, t) for t in comp.tasks]
    )
    for kind, name, node in sorted(entries, key=lambda e: (e[1].span.line, e[1].span.column)):
        if name.text in members:
            _duplicate(sink, kind, name, first[name.text],
                       message=f"`{name.text}` is declared more than once in component `{comp.name.text}`",
                       help="ports, compounds and tasks of a component share one namespace: rename or remove one")
            continue
        members[name.text] = (kind, node)
        first[name.text] = name
    scope = ComponentScope(comp, members)
    _check_component_refs(scope, sink)
    return scope


def _expect_member(scope: ComponentScope, name: s.Name, kinds: tuple[MemberKind, ...], code: str,
                   sink: DiagnosticSink, role: str, user: str | None = None) -> bool:
    """``name`` is a member of one of ``kinds``. ``role`` says what the name is used as ("trigger port");
    ``user``, if given, says who uses it ("task `T` reads") for a message in those words."""
    kind = scope.kind_of(name.text)
    comp = scope.name
    if kind is None:
        hint = suggest(name.text, scope.names(*kinds))
        expected = " or ".join(kinds)
        message = (f"{user} `{name.text}`, but component `{comp}` declares no {expected} of that name" if user
                   else f"{role} `{name.text}` is not declared by component `{comp}`")
        sink.emit(code, message, name.span, f"no {expected} of this name",
                  help=f"did you mean `{hint}`?" if hint
                  else f"declare `{name.text}` as {_article(expected)} of `{comp}`")
        return False
    if kind not in kinds:
        sink.emit("E107", f"`{name.text}` is {_article(kind)} of `{comp}`, but {_article(role)} must be "
                  + " or ".join(_article(k) for k in kinds), name.span, f"this is {_article(kind)}",
                  help=_kind_help(kinds, scope, name.text))
        return False
    return True


def _article(kind: str) -> str:
    return ("an " if kind[0] in "aeiou" else "a ") + kind


def _kind_help(kinds: tuple[MemberKind, ...], scope: ComponentScope, word: str) -> str:
    options = scope.names(*kinds)
    hint = suggest(word, options)
    if hint:
        return f"did you mean `{hint}`?"
    if options:
        return "candidates: " + ", ".join(f"`{o}`" for o in options)
    return f"component `{scope.name}` declares no {' or '.join(kinds)}"


def _check_component_refs(scope: ComponentScope, sink: DiagnosticSink) -> None:
    for comp_port in scope.component.compounds:
        seen: set[str] = set()
        for member in comp_port.members:
            _expect_member(scope, member, ("in-port",), "E101", sink, "compound member")
            if member.text in seen:
                sink.emit("E102", f"`{member.text}` is listed twice in compound `{comp_port.name.text}`",
                          member.span, "listed again", help="list every member once")
            seen.add(member.text)
    for task in scope.component.tasks:
        for read in task.reads:
            _expect_member(scope, read.port, ("in-port",), "E104", sink, "port a task reads",
                           user=f"task `{task.name.text}` reads")
        for out in task.produces:
            _expect_member(scope, out, ("out-port",), "E104", sink, "port a task produces",
                           user=f"task `{task.name.text}` produces")


def _scope_system(system: s.System, components: dict[str, ComponentScope], sink: DiagnosticSink) -> SystemScope:
    before = len([d for d in sink.items if d.severity.value == "error"])
    cores = _unique(system.cores, lambda c: c.name, "core", sink)
    for core in system.cores:
        if core.policy is not None and core.policy.text not in KNOWN_POLICIES:
            hint = suggest(core.policy.text, KNOWN_POLICIES)
            sink.emit("E106", f"unknown scheduling policy `{core.policy.text}`", core.policy.span,
                      "not a known policy",
                      help=f"did you mean `{hint}`?" if hint else "supported: " + ", ".join(KNOWN_POLICIES))
    executors = _scope_executors(system, cores, sink)
    instances = _unique(system.instances, lambda i: i.name, "instance", sink)
    component_of: dict[str, ComponentScope] = {}
    bindings: dict[tuple[str, str], s.TaskBinding] = {}
    for inst in system.instances:
        if inst.core is not None and inst.core.text not in cores:
            _unknown(sink, "core", inst.core, cores)
        scope = components.get(inst.component.text)
        if scope is None:
            _unknown(sink, "component", inst.component, components)
            continue
        component_of.setdefault(inst.name.text, scope)
        _resolve_bindings(inst, scope, cores, executors, bindings, sink)
    for conn in system.connections:
        _resolve_ref(conn.source, ("out-port",), instances, component_of, sink, "connection source")
        _resolve_ref(conn.target, ("in-port",), instances, component_of, sink, "connection target")
    _unique(system.chains, lambda c: c.name, "chain", sink)
    for chain in system.chains:
        for i, ref in enumerate(chain.refs):
            last = i == len(chain.refs) - 1 and i > 0
            kinds: tuple[MemberKind, ...] = ("out-port", "in-port", "task") if last else ("out-port",)
            _resolve_ref(ref, kinds, instances, component_of, sink, "chain element")
    after = len([d for d in sink.items if d.severity.value == "error"])
    return SystemScope(system, cores, instances, component_of, bindings, resolved=after == before,
                       executors=executors)


def _scope_executors(system: s.System, cores: dict[str, s.Core], sink: DiagnosticSink) -> dict[str, s.Executor]:
    """The executors by name (E102 for a second of one name), each of a known kind (E108) on a known core."""
    executors = _unique(system.executors, lambda e: e.name, "executor", sink)
    for ex in system.executors:
        if ex.kind.text not in KNOWN_EXECUTORS:
            hint = suggest(ex.kind.text, KNOWN_EXECUTORS)
            sink.emit("E108", f"unknown executor kind `{ex.kind.text}`", ex.kind.span, "not a known executor kind",
                      help=f"did you mean `{hint}`?" if hint else "supported: " + ", ".join(KNOWN_EXECUTORS))
        for core in ex.cores:
            if core.text not in cores:
                _unknown(sink, "core", core, cores)
    return executors


def _resolve_bindings(inst: s.Instance, scope: ComponentScope, cores: dict[str, s.Core],
                      executors: dict[str, s.Executor], bindings: dict[tuple[str, str], s.TaskBinding],
                      sink: DiagnosticSink) -> None:
    groups = _unique(inst.groups, lambda g: g.name, "callback group", sink)
    for group in inst.groups:
        if group.kind.text not in KNOWN_GROUPS:
            hint = suggest(group.kind.text, KNOWN_GROUPS)
            sink.emit("E108", f"unknown callback-group kind `{group.kind.text}`", group.kind.span,
                      "not a known callback-group kind",
                      help=f"did you mean `{hint}`?" if hint else "supported: " + ", ".join(KNOWN_GROUPS))
    for binding in inst.bindings:
        if not _expect_member(scope, binding.task, ("task",), "E101", sink, "task"):
            continue
        key = (inst.name.text, binding.task.text)
        if key in bindings:
            _duplicate(sink, "binding", binding.task, bindings[key].task,
                       message=f"task `{inst.name.text}.{binding.task.text}` is bound more than once",
                       help="bind every task once: merge the two bindings")
            continue
        bindings[key] = binding
        if binding.core is not None and binding.core.text not in cores:
            _unknown(sink, "core", binding.core, cores)
        if binding.executor is not None and binding.executor.text not in executors:
            _unknown(sink, "executor", binding.executor, executors)
        if binding.group is not None and binding.group.text not in groups:
            _unknown(sink, "callback group", binding.group, groups, f" in instance `{inst.name.text}`")
        for act in binding.activations:
            if isinstance(act, s.Trigger):
                _expect_member(scope, act.port, ("in-port", "compound in-port"), "E101", sink, "trigger port")


def _resolve_ref(ref: s.PortRef, kinds: tuple[MemberKind, ...], instances: dict[str, s.Instance],
                 component_of: dict[str, ComponentScope], sink: DiagnosticSink, role: str) -> bool:
    if ref.instance.text not in instances:
        _unknown(sink, "instance", ref.instance, instances)
        return False
    scope = component_of.get(ref.instance.text)
    if scope is None:  # its component is unknown: already reported
        return False
    return _expect_member(scope, ref.member, kinds, "E101", sink, role)


def _unique(nodes: Iterable[_Node], key: Callable[[_Node], s.Name], what: str,
            sink: DiagnosticSink) -> dict[str, _Node]:
    table: dict[str, _Node] = {}
    for node in nodes:
        name = key(node)
        if name.text in table:
            _duplicate(sink, what, name, key(table[name.text]))
        else:
            table[name.text] = node
    return table


def resolve(project: Project, sink: DiagnosticSink) -> Resolution:
    """Resolve every name in ``project``; every problem becomes a diagnostic in ``sink``."""
    components: dict[str, ComponentScope] = {}
    for comp in project.components:
        if comp.name.text in components:
            _duplicate(sink, "component", comp.name, components[comp.name.text].component.name)
            continue
        components[comp.name.text] = _scope_component(comp, sink)
    messages = _messages(project, sink)
    systems: dict[str, SystemScope] = {}
    for system in project.systems:
        if system.name.text in systems:
            _duplicate(sink, "system", system.name, systems[system.name.text].system.name)
            continue
        systems[system.name.text] = replace(_scope_system(system, components, sink), messages=messages)
    return Resolution(components, systems, messages)


#: a ROS message: a package name (REP 144: lower-case letters, digits, ``_``, from a letter), then a
#: message name both ROS 1 and ROS 2 accept (letters and digits, from an upper-case letter); ROS 2's
#: ``msg/`` between them is optional
ROS_MESSAGE = re.compile(r"([a-z][a-z0-9_]*)/(?:msg/)?([A-Z][A-Za-z0-9]*)")


def ros_message(text: str) -> tuple[str, str] | None:
    """The package and the message name of a ROS message's name (``sensor_msgs/LaserScan`` or
    ``sensor_msgs/msg/LaserScan``), or None if ``text`` is not one."""
    found = ROS_MESSAGE.fullmatch(text)
    return (found.group(1), found.group(2)) if found else None


def _messages(project: Project, sink: DiagnosticSink) -> dict[str, s.Message]:
    """The valid message declarations of the project, by message type; E102 for a type declared twice,
    E109 for a ROS name that is not one."""
    messages: dict[str, s.Message] = {}
    first: dict[str, s.Name] = {}
    for message in (m for module in project.modules for m in module.messages):
        if message.name.text in first:
            _duplicate(sink, "message type", message.name, first[message.name.text])
            continue
        first[message.name.text] = message.name
        if ros_message(message.ros) is None:
            sink.emit("E109", f"`{message.ros}` is not the name of a ROS message", message.ros_span,
                      "expected PACKAGE/NAME", help="write the package, then the message: `sensor_msgs/LaserScan` "
                      "(a package is lower-case letters, digits and `_`; a message starts with an upper-case letter)")
            continue
        messages[message.name.text] = message
    return messages
