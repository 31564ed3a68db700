"""``verify trace`` without the command line: read the traces, pair, measure, find (specs/trace.md)."""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from ..core.diagnostics import Diagnostic, DiagnosticSink
from ..frontend.loader import Project
from ..model.system import SystemModel
from ..core.source import Span
from ..timing import AnalysisResult, analyze
from .delays import Delays, delay_findings, measure_delays
from .findings import PERIOD_TOLERANCE, findings
from .match import Matching, match
from .metrics import Measurements, measure
from .recording import Recording


@dataclass(frozen=True)
class TraceResult:
    system: str
    recording: Recording
    matching: Matching
    measured: Measurements
    analysis: AnalysisResult
    diagnostics: tuple[Diagnostic, ...]
    delays: Delays = Delays((), ())  # the connections' measured delays (LTTng traces with message links)


def read_traces(paths: Sequence[str], sink: DiagnosticSink) -> Recording | None:
    """The recording of ``paths``: LTTng trace directories, job-record files (``.jsonl``) or directories
    holding them, or bags (ROS 1 ``.bag`` files, ROS 2 bag directories); None after E806 when they
    cannot be read."""
    from ..core.fileaccess import Refused
    from . import bags, jobrecords, lttng

    given = tuple(paths)
    where = Span(given[0] if given else "<command line>", 1, 1, 1, 1)
    kinds = {bags.is_bag(p) for p in given}
    try:
        if kinds != {True}:  # (a directory of job records, as the ROS 2 nodes write them, is its files)
            given = tuple(f for p in given for f in _record_files(p))
        records = [p for p in given if not os.path.isdir(p)]
        if kinds == {True}:
            return bags.read(given)
        if True in kinds:
            sink.emit("E806", "bags and other traces are read apart", where, "mixed",
                      help="give either bags (ROS 1 `.bag` files, ROS 2 bag directories) or other traces")
            return None
        if records and len(records) == len(given):
            return jobrecords.read(given)
        if records:
            sink.emit("E806", "LTTng trace directories and job-record files are read apart: "
                      + ", ".join(records) + " is not a directory", where, "mixed",
                      help="give either LTTng trace directories or job-record files (.jsonl)")
            return None
        return lttng.read(given)
    except bags.NotBag as err:
        sink.emit("E806", f"{', '.join(given)} cannot be read as a bag: {err}", where, "not a bag",
                  help="give a ROS 1 `.bag` file or a ROS 2 bag directory (`ros2 bag record` writes it)")
    except jobrecords.NotRecords as err:
        sink.emit("E806", f"{err}", where, "not a trace", help="give an LTTng trace directory (`ros2 trace`, "
                  "CARET's recording) or the job records of the generated nodes (one JSON object a line)")
    except lttng.Unreadable as err:
        sink.emit("E806", f"{', '.join(given)} cannot be read as an LTTng trace: {err}", where, "not a trace",
                  help="give the directory `ros2 trace` or `lttng` wrote (it holds `metadata` and the streams)")
    except lttng.Unavailable as err:
        sink.emit("E806", f"LTTng traces cannot be read here: {err}", where, "not read",
                  help="install babeltrace2's Python bindings (`scripts/install-tools`)")
    except Refused as err:
        why = {"missing": "there is no such file", "special": "it is not a regular file (a device, a pipe)",
               "directory": "it is a directory", "link": "it is a symbolic link"}.get(err.reason, err.reason)
        sink.emit("E806", f"{err.path} cannot be read: {why}", where, "cannot be read",
                  help="name an existing trace directory or job-record file")
    except OSError as err:
        sink.emit("E806", f"{', '.join(given)} cannot be read: {err.strerror or err}", where, "cannot be read",
                  help="name an existing trace directory or job-record file")
    return None


def _record_files(path: str) -> tuple[str, ...]:
    """``path``, or the job-record files of the directory ``path`` when it is one of those."""
    from . import jobrecords

    return (jobrecords.files_in(path) if os.path.isdir(path) else ()) or (path,)


def trace_system(model: SystemModel, project: Project, recording: Recording, *,
                 tolerance: Fraction = PERIOD_TOLERANCE) -> TraceResult:
    """The measurements of ``recording`` against ``model``, with the findings."""
    matching = match(model, recording)
    measured = measure(model, recording, matching)
    delays = measure_delays(model, recording)
    analysis = analyze(model)
    sink = DiagnosticSink()
    findings(model, analysis, recording, matching, measured, project, sink, tolerance, delays)
    delay_findings(model, delays, project, sink)
    return TraceResult(model.name, recording, matching, measured, analysis,
                       tuple(sorted(sink.items, key=Diagnostic.sort_key)), delays)
