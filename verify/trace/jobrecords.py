"""The job records of the generated nodes (specs/codegen.md §3, ``trace`` launch argument): one JSON
object per job — ``node``, ``task``, ``seq``, ``release``, ``start``, ``finish`` in nanoseconds — one a
line, as published on ``/verify/jobs`` (specs/trace.md §1.2). A line may also be a recorder's
``{"topic": "/verify/jobs", "data": "<the record>"}``; lines of other topics are skipped. A line that is
no record is counted and the recording labelled partial. Read as a stream, line by line.

A second record format (the ROS 2 generator's, when it lands) is one more ``read_*`` here or one more
module beside this one giving a ``Recording``.
"""
from __future__ import annotations

import json
import os

from ..core.fileaccess import open_regular
from .recording import Callback, Jobs, Recording

FIELDS = ("node", "task", "release", "start", "finish")
#: the suffix that names a job-records file on the command line
SUFFIXES = (".jsonl", ".ndjson")


class NotRecords(Exception):
    """The file holds no job record: the message says what it holds instead."""


def read(paths: tuple[str, ...]) -> Recording:
    """The jobs recorded in ``paths``."""
    out = Recording(paths, "job records")
    bad: list[str] = []
    for path in paths:
        fd = open_regular(path)
        with os.fdopen(fd, "rb") as fh:
            for number, raw in enumerate(fh, 1):
                _line(raw, out, bad, f"{path}:{number}")
    if not any(len(j) for j in out.jobs.values()):
        raise NotRecords(f"no job record in {', '.join(paths)}" + (f" ({len(bad)} line(s) not records: first "
                                                                      f"{bad[0]})" if bad else ""))
    if bad:
        out.partial.append(f"{len(bad)} line(s) are not job records and were left out (the first: {bad[0]})")
    return out


def _line(raw: bytes, out: Recording, bad: list[str], where: str) -> None:
    if not raw.strip():
        return
    out.events += 1
    try:
        item = json.loads(raw)
        if isinstance(item, dict) and "topic" in item and "node" not in item:
            if item.get("topic") != "/verify/jobs":
                out.ignored[str(item.get("topic"))] += 1
                return
            item = json.loads(item["data"])
        if not isinstance(item, dict):
            raise ValueError("not an object")
        node, task = item["node"], item["task"]
        release, start, finish = (item[k] for k in ("release", "start", "finish"))
        if not (isinstance(node, str) and isinstance(task, str)
                and all(type(v) is int and v >= 0 for v in (release, start, finish)) and start <= finish):
            raise ValueError("a field of the wrong type")
    except (ValueError, KeyError, TypeError, RecursionError):
        bad.append(where)
        return
    key = f"{node}\t{task}"
    if key not in out.callbacks:
        out.callbacks[key] = Callback(key, node, "task", task=task, registered=len(out.callbacks))
        out.jobs[key] = Jobs()
    jobs = out.jobs[key]
    jobs.add(start, finish, finish)
    jobs.releases.append(release)
