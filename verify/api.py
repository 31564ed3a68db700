"""The library façade: load a project and get its semantic models plus every diagnostic.

    result = verify.load("examples/navigation/navigation.vfy")
    if result.ok:
        model = result.system()          # the one system of the root file (or by name)

The pipeline is parse → resolve → validate → build model → chain checks; each stage reports all it
finds and later stages run only on what the earlier ones accepted.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

from .core.diagnostics import Diagnostic, DiagnosticSink, Label, has_errors
from .core.gcpause import paused_gc
from .core.limits import DEFAULT_LIMITS, Limits
from .frontend.loader import Overlay, Project, load_project, project_from_text
from .frontend.roots import project_roots
from .frontend.build import build_system
from .model.system import SystemModel
from .frontend.resolve import Resolution, SystemScope, resolve
from .core.source import SourceFile, Span
from .frontend.validate import validate, validate_chains

if TYPE_CHECKING:
    from .frontend.symbols import SymbolIndex


class SelectionError(Exception):
    """A command asked for a system the project does not have (exit code 2)."""

    def __init__(self, diagnostic: Diagnostic):
        super().__init__(diagnostic.message)
        self.diagnostic = diagnostic


@dataclass(frozen=True)
class LoadResult:
    project: Project
    resolution: Resolution | None
    models: dict[str, SystemModel] = field(compare=False)
    diagnostics: tuple[Diagnostic, ...] = ()

    @property
    def ok(self) -> bool:
        return not has_errors(self.diagnostics)

    @property
    def sources(self) -> dict[str, SourceFile]:
        return self.project.sources

    @cached_property
    def symbols(self) -> SymbolIndex:
        """Every declared name and every resolved use of one (``verify.frontend.symbols``), built on first use."""
        from .frontend.symbols import index

        return index(self.resolution) if self.resolution is not None else SymbolIndex((), ())

    def root_system_names(self) -> list[str]:
        root = self.project.root_module
        return [sy.name.text for sy in root.systems] if root else []

    def system(self, name: str | None = None) -> SystemModel:
        """The named system, or the only system of the root file."""
        sink = DiagnosticSink()
        names = self.root_system_names()
        where = Span(self.project.root, 1, 1, 1, 1)
        systems = {sy.name.text: sy for sy in self.project.root_module.systems} if self.project.root_module else {}
        if name is None:
            if len(names) != 1:
                found = ", ".join(f"`{n}`" for n in names) or "none"
                listed = list(systems.values())
                secondary: tuple[Label, ...] = ()
                if len(listed) > 1:  # point at the second system, the first one as context
                    where, secondary = listed[1].name.span, (Label(listed[0].name.span, "first system"),)
                sink.emit("E105", f"{self.project.root} must hold exactly one system to choose from "
                          f"(found {found})", where, "a second system" if len(listed) > 1 else "",
                          secondary=secondary, help="name one with `--system NAME`")
                raise SelectionError(sink.items[0])
            name = names[0]
        if name not in self.models:
            from .core.diagnostics import suggest

            if name in systems:
                sink.emit("E105", f"system `{name}` in {self.project.root} is not valid", systems[name].name.span,
                          "has errors", help="fix the errors `verify check` reports for it")
                raise SelectionError(sink.items[0])
            hint = suggest(name, names)
            if hint in systems:
                where = systems[hint].name.span
            sink.emit("E105", f"no system `{name}` in {self.project.root}", where,
                      "the closest system" if hint in systems else "",
                      help=f"did you mean `{hint}`?" if hint else "systems here: " + (", ".join(names) or "none"))
            raise SelectionError(sink.items[0])
        return self.models[name]


def require_configured(model: SystemModel, command: str) -> list[Diagnostic]:
    """E218 for every synthesis hole: ``analyze`` and ``prove`` need every activation bound."""
    sink = DiagnosticSink()
    for task in model.holes:
        sink.emit("E218", f"`{command}` needs a configured system, but `{task.id}` has a synthesis hole",
                  task.activation.span, "left open for synthesis",
                  help=f"run `synth` to fill the holes (`synth FILE -o configured.vfy`), then `{command}` the result")
    return sink.items


def finish_load(project: Project, sink: DiagnosticSink) -> LoadResult:
    """The result of loading a parsed ``project``: resolution, validation, the models of the valid systems
    and their chain checks; ``sink`` holds what loading reported so far (parsing, files)."""
    if not project.modules:
        return LoadResult(project, None, {}, tuple(sorted(sink.items, key=Diagnostic.sort_key)))
    resolution = resolve(project, sink)
    validate(resolution, sink)
    models: dict[str, SystemModel] = {}
    for name, scope in resolution.systems.items():
        if not scope.resolved or not _clean(scope, sink):
            continue
        model = build_system(scope)
        before = len(sink.items)
        validate_chains(scope, model, sink)
        check_propagated_rates(model, sink)
        if len(sink.items) == before:
            models[name] = model
    diagnostics = tuple(sorted(without_follow_on_errors(sink.items), key=Diagnostic.sort_key))
    return LoadResult(project, resolution, models, diagnostics)


#: errors after which part of a file is unread: a syntax error (what follows it up to where the parser
#: recovers) or a file, imported or not, that cannot be read, decoded or opened
UNREAD = frozenset({"E001", "E002", "E003", "E004", "E006", "E007", "E008"})
#: the same, for the file the error is in (an unreadable import is reported in the importing file)
UNPARSED = frozenset({"E001", "E002", "E003"})


def without_follow_on_errors(diagnostics: list[Diagnostic]) -> list[Diagnostic]:
    """Only the root errors while part of the project is unread (as rustc and mypy report): no "unknown
    name" (E101: its declaration may be in what was not read), and in a file with a syntax error none
    but its syntax errors (the rest may follow from the parser's recovery). Warnings stay."""
    if not any(d.code in UNREAD for d in diagnostics):
        return diagnostics
    unparsed = {d.span.file for d in diagnostics if d.code in UNPARSED}
    return [d for d in diagnostics if d.severity != "error" or d.code.startswith("E0")
            or (d.code != "E101" and d.span.file not in unparsed)]


#: what ``check_propagated_rates`` reports: the constraints of triggered tasks (E305/E306) and of
#: compound in-ports (E314) against their propagated rates (the rates stage reports more, e.g. sampling
#: tolerances, which stay with ``analyze``)
RATE_CODES = frozenset({"E305", "E306", "E314"})


def check_propagated_rates(model: SystemModel, sink: DiagnosticSink) -> None:
    """E305/E306 for a data-triggered task whose propagated rate leaves its activation constraint, and
    E314 for such a compound in-port (specs/language.md §4), computed by the rates stage of the timing
    analysis. A task whose rate is
    not bounded (a synthesis hole or a trigger cycle upstream) is not checked here: ``synth`` and
    ``analyze`` deal with it."""
    from .timing.rates import activation_rates, check_trigger_constraints

    found = DiagnosticSink()
    check_trigger_constraints(model, activation_rates(model), found)
    for d in found.items:
        if d.code in RATE_CODES:
            sink.add(d)


def _clean(scope: SystemScope, sink: DiagnosticSink) -> bool:
    """No error lies inside the system or inside a component it instantiates."""
    files_lines = [scope.system.span] + [c.component.span for c in scope.component_of.values()]
    for d in sink.items:
        if d.severity.value != "error":
            continue
        for region in files_lines:
            if d.span.file == region.file and region.line <= d.span.line <= region.end_line:
                return False
    return True


def load(path: str | os.PathLike[str], *, root: str | os.PathLike[str] | None = None,
         include: tuple[str, ...] | list[str] = (),
         limits: Limits = DEFAULT_LIMITS, overlay: Overlay | None = None,
         config: bool = True) -> LoadResult:
    """Load, resolve and validate the project whose root file is ``path`` (imports followed).

    Imports are confined to the project root — ``root``, else the ``root`` of ``[tool.verify]`` in the
    nearest ``pyproject.toml`` (``config``), else the directory of ``path`` — and the library directories
    ``include`` (and that table's ``include``); ``verify.frontend.roots`` gives the rules. ``limits`` bound what is
    read (``verify.core.limits``). ``overlay`` gives text that takes the place of a file on disk (an editor's
    unsaved buffers): a mapping from paths, or a function of an absolute path returning the text or
    None."""
    path = os.fspath(path)
    root = os.fspath(root) if root is not None else None
    with paused_gc():
        sink = DiagnosticSink()
        roots, problems = project_roots(path, root, tuple(include), config=config) if path else (None, [])
        sources = {}
        for p in problems:
            sink.emit(p.code, p.message, p.span, p.label, help=p.help)
            if p.text:
                sources[p.span.file] = SourceFile(p.span.file, p.text)
        if problems:
            return LoadResult(Project(os.path.normpath(path), (), sources), None, {}, tuple(sink.items))
        project = load_project(path, sink, roots=roots, limits=limits, overlay=overlay)
        return finish_load(project, sink)


def load_text(text: str, path: str = "<text>", *, limits: Limits = DEFAULT_LIMITS) -> LoadResult:
    """The same for text in memory (one file; imports are not followed)."""
    with paused_gc():
        sink = DiagnosticSink()
        project = project_from_text(text, path, sink, limits)
        return finish_load(project, sink)
