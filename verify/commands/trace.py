"""``verify trace MODEL TRACE...``: what the robot measured, held against the model (specs/trace.md).

TRACE is an LTTng trace directory (ros2_tracing, CARET), a file of the generated nodes' job records
(``.jsonl``), or a bag (ROS 1 ``.bag``, ROS 2 bag directory); several of one kind are read as one run.
The measurements go to standard output, the findings (E801–E807) to standard error; ``--format
json|sarif`` prints one document instead.

``--calibrate`` writes the measured execution times and connection delays into the model (``--margin``, default 20 %):
without ``-o``/``--in-place`` the calibrated file goes to standard output (``--diff``: a unified diff);
the model is changed only with ``--in-place``. A model that does not load only for want of `wcet`s,
priorities or cores (an imported one) is calibrated through a stand-in (``verify.trace.standin``).

Exit codes: 0 the measurements agree with the model (alarms E803, E807 may be shown); 1 a measurement
contradicts it (E801 execution time above the wcet, E802 period off the model, E804 a spec exceeded);
2 invalid input or usage (a model that does not load, a trace that cannot be read: E806); 70 internal error.
"""
from __future__ import annotations

import argparse
from fractions import Fraction
from typing import TYPE_CHECKING

from ..outputs import Report, render
from .common import (EXIT_INVALID, EXIT_OK, EXIT_VIOLATED, fail, load_configured, replace_file, show,
                     show_diagnostics, to_stderr, write_new_file)

if TYPE_CHECKING:
    from .. import api
    from ..model.system import SystemModel
    from ..trace.run import TraceResult

HELP = "measurements of the robot (LTTng traces, job records, bags) against the model; --calibrate writes them in"
RESULT = "trace"
MODEL, SYSTEM = True, True


def _percent(text: str) -> Fraction:
    try:
        value = Fraction(text.rstrip("%")) / 100
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"not a percentage: {text!r}") from None
    if value < 0 or value > 10:
        raise argparse.ArgumentTypeError(f"{text} is not between 0 and 1000 %")
    return value


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("traces", metavar="TRACE", nargs="+",
                   help="an LTTng trace directory (ros2_tracing, CARET), a job-records file (.jsonl) of the "
                        "generated nodes, or a bag (ROS 1 .bag, ROS 2 bag directory)")
    p.add_argument("--tolerance", metavar="PERCENT", type=_percent, default=Fraction(1, 100),
                   help="how far a timer's mean measured period may be off the model (default 1)")
    p.add_argument("--calibrate", action="store_true",
                   help="write the measured execution times (bcet, wcet) and connection delays into the model")
    p.add_argument("--margin", metavar="PERCENT", type=_percent, default=None,
                   help="with --calibrate: the margin on the greatest measured execution time and delay (default 20)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("-o", "--output", metavar="OUT", help="with --calibrate: write the calibrated file to OUT")
    where.add_argument("--diff", action="store_true", help="with --calibrate: print a unified diff instead")
    where.add_argument("--in-place", action="store_true", help="with --calibrate: rewrite FILE itself")
    p.add_argument("--force", action="store_true", help="with -o: replace OUT if it exists")


def run(args: argparse.Namespace) -> int:
    from ..core.diagnostics import DiagnosticSink
    from ..trace.run import read_traces, trace_system

    if (args.output or args.diff or args.in_place or args.margin is not None) and not args.calibrate:
        return fail("-o, --diff, --in-place and --margin go with --calibrate")
    if args.calibrate and args.file == "-" and args.in_place:
        return fail("--in-place needs a file, not standard input (`-`)")
    stand_in = _stand_in(args) if args.calibrate else None
    loaded = stand_in or load_configured(args, "trace")
    if isinstance(loaded, int):
        return loaded
    result, system = loaded[0], loaded[1]
    sink = DiagnosticSink()
    recording = read_traces(args.traces, sink)
    if recording is None:
        show_diagnostics(args, sink.items, result.sources)
        return EXIT_INVALID
    traced = trace_system(system, (stand_in[2] if stand_in else result).project, recording, tolerance=args.tolerance)
    if args.calibrate:
        return _calibrate(args, result, system, traced)
    show(render(RESULT, args.format, Report(RESULT, args.file, traced.diagnostics, result.sources, traced, system)))
    return EXIT_VIOLATED if any(d.severity.value == "error" for d in traced.diagnostics) else EXIT_OK


def _stand_in(args: argparse.Namespace) -> tuple[api.LoadResult, SystemModel, api.LoadResult] | None:
    """For a model that does not load only for want of `wcet`s, priorities or cores (as `verify import
    caret` writes it): (the model as loaded, the system of its stand-in, the stand-in as loaded) —
    ``verify.trace.standin``; None otherwise (the model loads, or fails for other reasons)."""
    from .. import api
    from ..trace.standin import only_gaps, stand_in_text
    from .common import load_args

    if args.file == "-":
        return None  # (standard input is read once: by the ordinary load)
    loaded = load_args(args)
    root = loaded.project.root_module
    if loaded.ok or root is None or not only_gaps(loaded.diagnostics) or loaded.project.root not in loaded.sources:
        return None
    text = stand_in_text(root, loaded.sources[loaded.project.root])
    stand_in = api.load(loaded.project.root, root=args.root, include=tuple(args.include or ()),
                        overlay={loaded.project.root: text})
    if not stand_in.ok:
        return None
    try:
        system = stand_in.system(args.system)
    except api.SelectionError:
        return None
    return (loaded, system, stand_in) if not api.require_configured(system, "trace") else None


def _calibrate(args: argparse.Namespace, loaded: api.LoadResult, system: SystemModel, traced: TraceResult) -> int:
    from .. import api
    from ..synth.writeback import unified_diff
    from ..trace.calibrate import DEFAULT_MARGIN, calibrate
    from ..trace.standin import only_gaps
    from ..model.units import fmt_time

    root = loaded.project.root_module
    assert root is not None, "a loaded model has its root module"
    source = loaded.sources[loaded.project.root]
    done = calibrate(root, source, system, traced.measured, DEFAULT_MARGIN if args.margin is None else args.margin,
                     traced.delays)
    check = api.load(loaded.project.root, root=args.root, include=tuple(args.include or ()),
                     overlay={loaded.project.root: done.text})
    # (a model calibrated through a stand-in may keep its gaps: priorities and cores are the integrator's)
    if not check.ok and not (not loaded.ok and only_gaps(check.diagnostics)):  # (never written: a bug)
        raise RuntimeError("the calibrated model does not load: " + "; ".join(d.message for d in check.diagnostics))
    if not check.ok:
        left = sorted({d.code for d in check.diagnostics if d.severity.value == "error"})
        to_stderr(f"note: the calibrated model still lacks what a trace does not measure ({', '.join(left)}: "
                  "priorities, cores): `verify check` lists them")
    for c in done.changes:
        new = f"{fmt_time(c.new_min)} .. {fmt_time(c.new)}" if c.new_min is not None else fmt_time(c.new)
        to_stderr(f"{c.subject}: {c.what} {fmt_time(c.old) if c.old is not None else '(none)'} -> {new}")
    for what in done.elsewhere:
        named = what if what.startswith("connection ") else f"component `{what}`"
        to_stderr(f"note: {named} is not in {args.file} (or its task is on one line): not calibrated")
    if args.diff:
        print(unified_diff(source.text, done.text, args.file).replace("(synthesized)", "(calibrated)"), end="")
        return EXIT_OK
    if args.in_place:
        return replace_file(args.file, done.text) if done.text != source.text else EXIT_OK
    if args.output:
        return write_new_file(args.output, done.text, args.force)
    print(done.text, end="")
    return EXIT_OK
