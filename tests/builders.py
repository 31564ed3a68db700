"""Builders shared by tests: semantic models constructed directly in Python, a model traced."""
from __future__ import annotations

from fractions import Fraction as F

import verify
from verify.core.diagnostics import DiagnosticSink
from verify.model.system import LinkModel
from verify.trace.run import read_traces, trace_system


def link(source, target, tasks, dmin=F(0), dmax=None):
    """The connection ``source`` → ``target`` ("inst.port"), its writer and readers found in ``tasks``."""
    src_inst, src_port = source.split(".")
    dst_inst, dst_port = target.split(".")
    writer = next(t.id for t in tasks if t.instance == src_inst and src_port in t.produces)
    readers = tuple(t.id for t in tasks if t.instance == dst_inst and t.reads_port(dst_port))
    return LinkModel(source, target, writer, readers, dmin, dmin if dmax is None else dmax)


def traced(model_path, traces):
    """``verify trace``'s result for the model at ``model_path`` and the recordings ``traces``."""
    loaded = verify.load(str(model_path))
    sink = DiagnosticSink()
    recording = read_traces(traces, sink)
    assert recording is not None, [d.message for d in sink.items]
    return trace_system(loaded.system(None), loaded.project, recording)


def project_files(project):
    """Every file under ``project`` (a generated project): its bytes by its path relative to ``project``."""
    return {p.relative_to(project).as_posix(): p.read_bytes() for p in sorted(project.rglob("*")) if p.is_file()}
