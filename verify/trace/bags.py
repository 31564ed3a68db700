"""Topic timestamps from recorded bags (specs/trace.md §1.3): a ROS 1 bag (``*.bag``) or a ROS 2 bag
(a directory with ``metadata.yaml``: MCAP or SQLite storage), read with ``rosbags`` (the ``trace``
extra) as a stream, message by message, without deserializing a message.

Each topic is one recorded "callback" of kind ``topic``: a message is a job that starts and ends at
the time the bag recorded it. A bag measures how often each topic was written — the activation of the
task producing it — not how long a task ran, nor a chain (its jobs have no start and end).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from .recording import Callback, Jobs, Recording


class NotBag(Exception):
    """The bags cannot be read: the message says why."""


def is_bag(path: str) -> bool:
    return path.endswith(".bag") or (os.path.isdir(path) and os.path.exists(os.path.join(path, "metadata.yaml")))


def read(paths: Sequence[str]) -> Recording:
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.interfaces import Connection
    except ImportError:
        raise NotBag("bags are read with `rosbags`: install verify with the `trace` extra "
                     "(`pip install 'verify-timing[trace]'`)") from None
    out = Recording(tuple(paths), "bag")
    try:
        with AnyReader([Path(p) for p in paths]) as reader:
            connection: Connection
            for connection, timestamp, _ in reader.messages():
                _add(out, connection.topic, timestamp)
    except Exception as err:  # (rosbags reports a broken bag by several error classes of its own)
        if out.events == 0:
            raise NotBag(f"{type(err).__name__}: {err}") from None
        out.partial.append(f"the bag breaks off after {out.events:,} messages: {err}")
    if out.events == 0:
        raise NotBag("the bag holds no message")
    return out


def _add(out: Recording, topic: str, timestamp: int) -> None:
    out.events += 1
    jobs = out.jobs.get(topic)
    if jobs is None:
        out.callbacks[topic] = Callback(topic, None, "topic", topic=topic, registered=len(out.callbacks))
        jobs = out.jobs[topic] = Jobs()
    jobs.add(timestamp, timestamp, timestamp)
