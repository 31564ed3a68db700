"""The job records of the generated nodes, one JSON object a line (specs/trace.md §1.2), in either of the
generators' formats, told apart line by line:

- the ROS 1 nodes' (specs/codegen.md §3, launch argument ``trace``), as published on ``/verify/jobs``:
  ``node`` (``/SYSTEM/INSTANCE``), ``task`` (its name), ``seq``, ``release``, ``start``, ``finish`` in
  nanoseconds, and ``reads``: per in-port read, the number of the writer's job it read (0: a value
  without one). A line may also be a recorder's ``{"topic": "/verify/jobs", "data": "<the record>"}``;
  lines of other topics are skipped;
- the ROS 2 nodes' (specs/codegen.md §9.4, ``TRACE_DIR/UNIT.jsonl``): ``unit`` (the process), ``task``
  (``INSTANCE.TASK``), ``seq``, ``release``, ``start``, ``finish``, and ``reads``: per in-port, null or
  the writer's ``[process, task, job number, message index]``.

Both may hold ``cpu``: the CPU time the job's thread spent from its start to its finish (ns, the
thread's CPU clock), the job's execution time; without it the execution time is finish − start.
``seq`` and ``reads`` are optional (records without them are measured by inference, metrics.py). A
line that is no record is counted and the recording labelled partial. Read as a stream, line by line;
what is kept is a few numbers a job (``Jobs``), not the records.
"""
from __future__ import annotations

import json
import os
from typing import Any

from ..core.fileaccess import open_regular
from .recording import Callback, Jobs, Recording

#: the suffix that names a job-records file on the command line
SUFFIXES = (".jsonl", ".ndjson")


class NotRecords(Exception):
    """The file holds no job record: the message says what it holds instead."""


class BadRecord(ValueError):
    """A line that is no job record."""


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


def files_in(directory: str) -> tuple[str, ...]:
    """The job-record files directly in ``directory`` (the ROS 2 nodes' ``TRACE_DIR``), in name order;
    none when it is an LTTng trace (it holds a CTF ``metadata`` file somewhere below)."""
    names = sorted(os.listdir(directory))
    found = tuple(os.path.join(directory, n) for n in names if n.endswith(SUFFIXES)
                  and os.path.isfile(os.path.join(directory, n)))
    if not found:
        return ()
    for _root, _dirs, files in os.walk(directory):
        if "metadata" in files:
            return ()
    return found


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
            raise BadRecord("not an object")
        _record(item, out)
    except (ValueError, KeyError, TypeError, RecursionError):
        bad.append(where)


def _time(value: Any) -> int:
    if type(value) is not int or value < 0:
        raise BadRecord("a time that is no whole number of nanoseconds")
    return value


def _record(item: dict[str, Any], out: Recording) -> None:
    ros2 = "unit" in item and "node" not in item
    node, task = item["unit" if ros2 else "node"], item["task"]
    release, start, finish = (_time(item[k]) for k in ("release", "start", "finish"))
    seq = _time(item.get("seq", 0))
    cpu = _time(item["cpu"]) if "cpu" in item else -1
    if not (isinstance(node, str) and isinstance(task, str) and start <= finish):
        raise BadRecord("a field of the wrong type")
    reads = _reads_ros2(item["reads"]) if ros2 and "reads" in item else _reads_ros1(item.get("reads"))
    key = f"{node}\t{task}"
    if key not in out.callbacks:
        out.callbacks[key] = Callback(key, node, "task", task=task, registered=len(out.callbacks))
        out.jobs[key] = Jobs()
    jobs = out.jobs[key]
    jobs.add(start, finish, finish)
    jobs.releases.append(release)
    jobs.seqs.append(seq)
    jobs.cpus.append(cpu)
    if reads is not None:
        if jobs.reads is None:
            jobs.reads = {}
        for port, writer, writer_seq in reads:
            jobs.read(port, writer, writer_seq)


def _reads_ros1(reads: Any) -> list[tuple[str, str, int]] | None:
    """A ROS 1 record's reads: per in-port the writer's job number (the port's writer is the model's)."""
    if reads is None:
        return None
    if not isinstance(reads, dict):
        raise BadRecord("reads that are no object")
    return [(str(port), "", _time(seq)) for port, seq in reads.items()]


def _reads_ros2(reads: Any) -> list[tuple[str, str, int]]:
    """A ROS 2 record's reads: per in-port null (no writer's job) or [process, task, job number, index]."""
    if not isinstance(reads, dict):
        raise BadRecord("reads that are no object")
    out = []
    for port, source in reads.items():
        if source is None:
            continue
        if not (isinstance(source, list) and len(source) == 4 and all(isinstance(s, str) for s in source[:2])):
            raise BadRecord("a read that is no [process, task, job, index]")
        _time(source[3])
        out.append((str(port), source[1], _time(source[2])))
    return out
