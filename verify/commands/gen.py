"""``verify gen TARGET FILE -o DIR``: the code that runs a configured system (specs/codegen.md).

Glue files (the generator's) are rewritten when their text changes; user files (the functional code's
skeletons, message types, build additions) are written once and never overwritten. A glue file that was
edited by hand, or a file in the way that the generator did not write, is never replaced (E601) unless
``--force`` is given; then nothing at all is written. A system with synthesis holes is refused (E218:
run ``synth`` first), and so is one the target cannot run (E602) or whose names would become one in the
generated code (E603). What the generated code does that the analysis does not charge (E605, a warning:
the ros2 target's processes taking arrivals while no ``arrival_cost`` is declared) is reported on
standard error. A write that fails midway reports what it wrote before the failure (E004).

Exit codes: 0 generated; 2 invalid input, holes, clashing names, a file in the way or a failed write;
70 internal error.
"""
from __future__ import annotations

import argparse
import os

from typing import TYPE_CHECKING

from ..core.diagnostics import Diagnostic, DiagnosticSink, Label
from ..core.fileaccess import Area, Refused, read_regular
from ..gen.tree import LINK
from ..core.sanitize import shown as printable
from ..outputs import Report, render
from ..core.source import SourceFile, Span
from .common import EXIT_INVALID, EXIT_OK, cannot_write, load_configured, show, show_diagnostics

if TYPE_CHECKING:
    from types import ModuleType

    from ..gen.tree import Outcome
    from ..model.system import SystemModel

HELP = "generate the code that runs a configured system (ROS 1 or ROS 2 nodes)"
RESULT = "generation"
MODEL, SYSTEM = True, True


def add_leading_arguments(p: argparse.ArgumentParser) -> None:
    from ..gen import TARGETS

    p.add_argument("target", metavar="TARGET", choices=TARGETS,
                   help=f"what to generate: {', '.join(TARGETS)} (specs/codegen.md)")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", metavar="DIR", required=True,
                   help="the directory of the generated project (created if missing)")
    p.add_argument("--force", action="store_true",
                   help="replace glue files that were edited by hand or not written by verify gen "
                        "(user files are never replaced)")


def refusals(outcome: Outcome, directory: str) -> tuple[list[Diagnostic], dict[str, SourceFile]]:
    """E601 for every file in the way (a glue file edited by hand, or a file gen did not write), and the
    files for their snippets (only their first line is shown)."""
    sink = DiagnosticSink()
    sources: dict[str, SourceFile] = {}
    for path, why in outcome.refused:
        full = os.path.join(directory, *path.split("/"))
        shown = printable(full)
        first = _first_line(full, directory) if why != LINK else ""
        span = Span(shown, 1, 1, 1, len(first) + 1)
        if first:
            sources[shown] = SourceFile(shown, first + "\n", only=span)
        help = ("remove the link; generated files are written only below the output directory, never through a "
                "link (--force does not change that); nothing was written") if why == LINK else \
            "move your changes into the user files (user/), or pass --force to replace it; nothing was written"
        sink.emit("E601", f"{shown} {why}; it is not replaced", span, why, help=help)
    return sink.items, sources


def _first_line(path: str, directory: str) -> str:
    """The first line of the regular file ``path`` in ``directory`` (at most 200 characters), or "" for
    anything else: a link is never followed, a FIFO or a device never opened (``verify.core.fileaccess``)."""
    try:
        data = read_regular(path, 200, Area((directory,)), follow_links=False)
    except (Refused, OSError):
        return ""
    return printable(data[:200].decode("utf-8", errors="replace").split("\n")[0].rstrip("\r"))


def unsupported_parts(module: ModuleType, name: str, system: SystemModel) -> list[Diagnostic]:
    """E602 for every part of ``system`` that target ``module`` cannot run as verified."""
    sink = DiagnosticSink()
    for span, what, help in getattr(module, "unsupported", lambda _model: [])(system):
        sink.emit("E602", what, span, f"not supported by the {name} target", help=help)
    return sink.items


def differing_semantics(module: ModuleType, name: str, system: SystemModel) -> list[Diagnostic]:
    """E604 for every part of ``system`` that target ``module``'s runtime would run otherwise than the
    analysis assumes (specs/codegen.md §9 for ros2)."""
    sink = DiagnosticSink()
    for span, what, help in getattr(module, "differs", lambda _model: [])(system):
        sink.emit("E604", what, span, f"the {name} target would not run it as analysed", help=help)
    return sink.items


def uncovered_parts(module: ModuleType, name: str, system: SystemModel) -> list[Diagnostic]:
    """E605 (a warning) for every part of ``system`` whose timing target ``module``'s runtime makes depend on
    what the model does not declare (specs/codegen.md §9.5 for ros2: the work of taking arrivals)."""
    sink = DiagnosticSink()
    for span, what, help in getattr(module, "uncovered", lambda _model: [])(system):
        sink.emit("E605", what, span, f"not covered by the analysis on the {name} target", help=help)
    return sink.items


def clashing_names(module: ModuleType, system: SystemModel) -> list[Diagnostic]:
    """E603 for every name of ``system`` that becomes, in target ``module``'s code, the name of another
    (a class, a file, a parameter, a node): one would overwrite or hide the other."""
    sink = DiagnosticSink()
    for span, other, what in getattr(module, "clashes", lambda _model: [])(system):
        sink.emit("E603", what, span, "clashes in the generated code", secondary=[Label(other, "the other name")],
                  help="rename one of them (specs/codegen.md, \"Names\": the generated code appends `_` to a name "
                       "C++ or ROS reserves); nothing was written")
    return sink.items


def run(args: argparse.Namespace) -> int:
    from ..gen import target
    from ..gen.tree import plan, write

    loaded = load_configured(args, "gen")
    if isinstance(loaded, int):
        return loaded
    result, system = loaded
    module = target(args.target)
    unsupported = (unsupported_parts(module, args.target, system) + differing_semantics(module, args.target, system)
                   + clashing_names(module, system))
    if unsupported:
        show_diagnostics(args, unsupported, result.sources)
        return EXIT_INVALID
    cautions = uncovered_parts(module, args.target, system)
    directory = args.output
    if os.path.exists(directory) and not os.path.isdir(directory):
        return cannot_write(directory, NotADirectoryError(20, "not a directory"))
    tree = module.generate(system)
    outcome = plan(tree, directory, args.force)
    if outcome.refused:
        diagnostics, files = refusals(outcome, directory)
        show_diagnostics(args, diagnostics, {**result.sources, **files})
        return EXIT_INVALID
    written: list[str] = []
    try:
        for path in write(tree, directory, outcome):
            written.append(path)
    except OSError as err:
        return cannot_write(getattr(err, "filename", None) or directory, err, written)
    show(render(RESULT, args.format, Report(RESULT, args.file, (), result.sources, outcome, system,
                                            {"directory": directory, "target": args.target})))
    if cautions:  # (on standard error, whatever the format: standard output stays the result)
        show(render("diagnostics", "text", Report("diagnostics", args.file, tuple(cautions), result.sources)))
    return EXIT_OK
