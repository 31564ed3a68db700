"""Builders shared by tests that construct semantic models directly in Python."""
from __future__ import annotations

from fractions import Fraction as F

from verify.model.system import LinkModel


def link(source, target, tasks, dmin=F(0), dmax=None):
    """The connection ``source`` → ``target`` ("inst.port"), its writer and readers found in ``tasks``."""
    src_inst, src_port = source.split(".")
    dst_inst, dst_port = target.split(".")
    writer = next(t.id for t in tasks if t.instance == src_inst and src_port in t.produces)
    readers = tuple(t.id for t in tasks if t.instance == dst_inst and t.reads_port(dst_port))
    return LinkModel(source, target, writer, readers, dmin, dmin if dmax is None else dmax)
