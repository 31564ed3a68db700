"""The symbols of a resolved project and where each is used: the table behind an editor's go to
definition, find references and rename (specs/language.md §2 gives the scopes).

``index(resolution)`` walks the syntax trees with the scopes name resolution built, so a use resolves
exactly as ``verify.frontend.resolve`` resolves it: a component's ports, compounds and tasks share one namespace;
an instance's members are its component's; an unknown name is no reference (``resolve`` reports it).

    idx = verify.load(path).symbols
    sym = idx.at("main.vfy", 9, 20)           # the symbol named at a position (a use or a declaration)
    idx.references_to(sym)                      # every use of it, in source order
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from typing import Literal

from ..model import syntax as s
from .resolve import ComponentScope, Resolution, SystemScope
from ..core.source import Span

SymbolKind = Literal["component", "system", "in-port", "out-port", "compound in-port", "task", "core", "instance",
                     "chain", "executor", "group"]


@dataclass(frozen=True)
class Symbol:
    """A declared name: what it is, its name, the component or system it belongs to ("" at the top
    level), the span of the name where it is declared and the declaring node."""

    kind: SymbolKind
    name: str
    container: str
    span: Span
    node: object = field(compare=False, repr=False)

    @property
    def key(self) -> tuple[str, str, str]:
        return (self.kind, self.container, self.name)


@dataclass(frozen=True)
class Reference:
    """A use of ``symbol``: the span of the name where it is used."""

    span: Span
    symbol: Symbol


@dataclass(frozen=True)
class SymbolIndex:
    symbols: tuple[Symbol, ...]
    references: tuple[Reference, ...]

    def __post_init__(self) -> None:
        names = sorted([(sym.span, sym) for sym in self.symbols] + [(ref.span, ref.symbol) for ref in self.references],
                       key=lambda item: (item[0].file, item[0].line, item[0].column))
        object.__setattr__(self, "_names", names)
        object.__setattr__(self, "_keys", [(sp.file, sp.line, sp.column) for sp, _ in names])

    def at(self, file: str, line: int, column: int) -> Symbol | None:
        """The symbol whose name (declared or used) covers 1-based (``line``, ``column``) of ``file``
        (a position just after the name counts, as an editor's cursor at the end of a word)."""
        names: list[tuple[Span, Symbol]] = self.__dict__["_names"]
        i = bisect.bisect_right(self.__dict__["_keys"], (file, line, column)) - 1
        while i >= 0:
            span, sym = names[i]
            if span.file != file or span.line != line:
                return None
            if span.column <= column <= span.end_column:
                return sym
            i -= 1
        return None

    def references_to(self, symbol: Symbol) -> list[Span]:
        """The spans of every use of ``symbol``, in source order (its declaration not included)."""
        return sorted((r.span for r in self.references if r.symbol.key == symbol.key),
                      key=lambda sp: (sp.file, sp.line, sp.column))

    def definition(self, kind: SymbolKind, name: str, container: str = "") -> Symbol | None:
        return next((sym for sym in self.symbols if sym.key == (kind, container, name)), None)


def index(resolution: Resolution) -> SymbolIndex:
    """Every declared name of ``resolution`` and every use name resolution resolved."""
    symbols: list[Symbol] = []
    references: list[Reference] = []
    components: dict[str, tuple[Symbol, dict[str, Symbol]]] = {}
    for name, scope in resolution.components.items():
        comp = Symbol("component", name, "", scope.component.name.span, scope.component)
        members = {m: Symbol(kind, m, name, node.name.span, node) for m, (kind, node) in scope.members.items()}
        symbols.append(comp)
        symbols.extend(members.values())
        components[name] = (comp, members)
        _component_uses(scope, members, references)
    for name, sys_scope in resolution.systems.items():
        symbols.append(Symbol("system", name, "", sys_scope.system.name.span, sys_scope.system))
        _system(sys_scope, components, symbols, references)
    return SymbolIndex(tuple(symbols), tuple(references))


def _use(references: list[Reference], name: s.Name, table: dict[str, Symbol], kinds: tuple[str, ...] = ()) -> None:
    sym = table.get(name.text)
    if sym is not None and (not kinds or sym.kind in kinds):
        references.append(Reference(name.span, sym))


def _component_uses(scope: ComponentScope, members: dict[str, Symbol], references: list[Reference]) -> None:
    for compound in scope.component.compounds:
        for member in compound.members:
            _use(references, member, members, ("in-port",))
    for task in scope.component.tasks:
        for read in task.reads:
            _use(references, read.port, members, ("in-port",))
        for out in task.produces:
            _use(references, out, members, ("out-port",))


def _system(scope: SystemScope, components: dict[str, tuple[Symbol, dict[str, Symbol]]], symbols: list[Symbol],
            references: list[Reference]) -> None:
    system = scope.name
    cores = {n: Symbol("core", n, system, c.name.span, c) for n, c in scope.cores.items()}
    instances = {n: Symbol("instance", n, system, i.name.span, i) for n, i in scope.instances.items()}
    executors = {n: Symbol("executor", n, system, e.name.span, e) for n, e in scope.executors.items()}
    symbols.extend(cores.values())
    symbols.extend(executors.values())
    symbols.extend(instances.values())
    for ex in scope.system.executors:
        for core in ex.cores:
            _use(references, core, cores)
    chains: dict[str, Symbol] = {}
    for chain in scope.system.chains:
        chains.setdefault(chain.name.text, Symbol("chain", chain.name.text, system, chain.name.span, chain))
    symbols.extend(chains.values())
    component_symbols = {name: comp for name, (comp, _) in components.items()}
    for inst in scope.system.instances:
        _use(references, inst.component, component_symbols)
        if inst.core is not None:
            _use(references, inst.core, cores)
        members = _members_of(scope, inst.name.text, components)
        groups: dict[str, Symbol] = {}
        for group in inst.groups:
            groups.setdefault(group.name.text, Symbol("group", group.name.text, system, group.name.span, group))
        symbols.extend(groups.values())
        for binding in inst.bindings:
            _use(references, binding.task, members, ("task",))
            if binding.core is not None:
                _use(references, binding.core, cores)
            if binding.executor is not None:
                _use(references, binding.executor, executors)
            if binding.group is not None:
                _use(references, binding.group, groups)
            for act in binding.activations:
                if isinstance(act, s.Trigger):
                    _use(references, act.port, members, ("in-port", "compound in-port"))
    refs = [ref for conn in scope.system.connections for ref in (conn.source, conn.target)]
    refs += [ref for chain in scope.system.chains for ref in chain.refs]
    for ref in refs:
        _use(references, ref.instance, instances)
        _use(references, ref.member, _members_of(scope, ref.instance.text, components))


def _members_of(scope: SystemScope, instance: str,
                components: dict[str, tuple[Symbol, dict[str, Symbol]]]) -> dict[str, Symbol]:
    comp = scope.component_of.get(instance)
    if comp is None or comp.name not in components:
        return {}
    return components[comp.name][1]
