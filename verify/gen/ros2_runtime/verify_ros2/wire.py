"""The wire (specs/codegen.md §6): a port's value as its plain ROS 2 message, and the writer job's
identity and chain stamps out of band, one record per message on ``TOPIC/verify`` (an
``std_msgs/msg/String`` holding JSON), correlated with its message by the digest of the message as
``serialize_message`` makes it (BLAKE2b, 8 bytes: the reader serializes what it received again, as the
wire may pad the bytes it carries) and, among equal digests, by their order."""
from __future__ import annotations

import hashlib
import importlib
import json
import threading
from collections import deque
from dataclasses import dataclass
from typing import Any

from .monitor import Stamp

#: how long a message whose record has not arrived yet waits for it, while a record publisher is there
RECORD_WAIT_S = 0.02
#: records kept per topic waiting for their message
MAX_WAITING = 100


def message_class(name: str | None) -> Any:
    """The Python class of ROS 2 interface ``pkg/msg/Name`` (None: std_msgs/msg/String, carrying JSON)."""
    package, _, type_name = (name or "std_msgs/msg/String").split("/")
    return getattr(importlib.import_module(f"{package}.msg"), type_name)


def digest(data: bytes) -> str:
    return hashlib.blake2b(data, digest_size=8).hexdigest()


@dataclass(frozen=True)
class Record:
    """What a message carries out of band: its writer (a process of the model), the job that wrote it."""

    writer: str
    index: int  # the message's number on its topic from this writer, from 1
    seq: int  # the writer job's number
    task: str
    release: int
    start: int
    finish: int
    event: int
    stamps: tuple[Stamp, ...]
    digest: str

    def encode(self) -> str:
        return json.dumps({"writer": self.writer, "index": self.index, "seq": self.seq, "task": self.task,
                           "release": self.release, "start": self.start, "finish": self.finish,
                           "event": self.event, "digest": self.digest,
                           "stamps": [[s.chain, s.position, s.origin, s.first] for s in self.stamps]})

    @staticmethod
    def decode(text: str) -> Record:
        d = json.loads(text)
        return Record(str(d["writer"]), int(d["index"]), int(d["seq"]), str(d["task"]), int(d["release"]),
                      int(d["start"]), int(d["finish"]), int(d["event"]),
                      tuple(Stamp(str(c), int(p), int(o), int(f)) for c, p, o, f in d["stamps"]), str(d["digest"]))


class Pairing:
    """Records of one topic waiting for their messages (filled by the records' thread)."""

    def __init__(self) -> None:
        self._waiting: dict[str, deque[Record]] = {}
        self._order: deque[str] = deque()
        self._cond = threading.Condition()

    def add(self, record: Record) -> None:
        with self._cond:
            self._waiting.setdefault(record.digest, deque()).append(record)
            self._order.append(record.digest)
            while len(self._order) > MAX_WAITING:
                self._take(self._order[0])
            self._cond.notify_all()

    def _take(self, key: str) -> Record | None:
        queue = self._waiting.get(key)
        if not queue:
            return None
        record = queue.popleft()
        if not queue:
            del self._waiting[key]
        self._order.remove(key)
        return record

    def take(self, key: str, wait: bool) -> Record | None:
        """The record of the message with digest ``key``: waits up to RECORD_WAIT_S for it if ``wait``."""
        with self._cond:
            if wait:
                self._cond.wait_for(lambda: key in self._waiting, RECORD_WAIT_S)
            return self._take(key)


def to_wire(value: Any, bound: bool) -> Any:
    """The message that carries ``value``: itself when bound, else its JSON in an std_msgs/msg/String."""
    if bound:
        return value
    return message_class(None)(data=json.dumps(value))


def from_wire(message: Any, bound: bool) -> Any:
    if bound:
        return message
    return json.loads(message.data)
