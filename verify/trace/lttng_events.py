"""The events an LTTng trace of ros2_tracing or CARET holds, and the reader's state as it sees them
(specs/trace.md §1.1): which events are read with which fields (``USED``), babeltrace2's bindings
(``bindings()``), and ``Reader``, which keeps the registrations and three numbers per job. The reading
itself, in a child process over a babeltrace2 graph, is ``verify.trace.lttng.read``.
"""
from __future__ import annotations

import functools
import importlib.util
import os
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from types import ModuleType

from ..interop.caret.read import IGNORED_TOPICS
from .links import Linker
from .recording import Callback, Jobs, Recording

#: the events read, with the fields each handler takes (ros2_tracing's names; CARET records the same)
USED: dict[str, tuple[str, ...]] = {
    "ros2:rcl_node_init": ("node_handle", "node_name", "namespace"),
    "ros2:rcl_timer_init": ("timer_handle", "period"),
    "ros2:rclcpp_timer_callback_added": ("timer_handle", "callback"),
    "ros2:rclcpp_timer_link_node": ("timer_handle", "node_handle"),
    "ros2:rcl_publisher_init": ("publisher_handle", "node_handle", "topic_name"),
    "ros2:rcl_subscription_init": ("subscription_handle", "node_handle", "rmw_subscription_handle", "topic_name"),
    "ros2:rclcpp_subscription_init": ("subscription_handle", "subscription"),
    "ros2:rclcpp_subscription_callback_added": ("subscription", "callback"),
    "ros2:rclcpp_callback_register": ("callback", "symbol"),
    "ros2:callback_start": ("callback",),
    "ros2:callback_end": ("callback",),
    "ros2:rcl_publish": ("publisher_handle", "message"),
    # a publish's source timestamp: ros2_tracing's (since Jazzy), CARET's
    "ros2:rmw_publish": ("message", "timestamp"),
    "ros2_caret:dds_bind_addr_to_stamp": ("addr", "source_stamp"),
    # a receipt, with the source timestamp of the message taken: ros2_tracing's, CARET's (whose field is
    # `source_stamp` in its early traces, `source_timestamp` later: "a|b" takes the one the event has)
    "ros2:rmw_take": ("rmw_subscription_handle", "source_timestamp", "taken"),
    "ros2:dispatch_subscription_callback": ("callback", "source_timestamp|source_stamp"),
    # intra-process: a publish (ros2_tracing's; CARET's adds `message_timestamp`: "?x" reads None without
    # it) and CARET's receipt, linked by message address and timestamp
    "ros2:rclcpp_intra_publish": ("publisher_handle", "message", "?message_timestamp"),
    "ros2:dispatch_intra_process_subscription_callback": ("callback", "message", "message_timestamp"),
}
#: what a reader's cache of the publishers and subscriptions linked holds for one not seen yet
_UNSEEN: tuple[str, str] = ("", "")
_UNSEEN_SUBSCRIPTION: tuple[str, str, tuple[int, int]] = ("", "", (0, 0))
#: where Debian installs the bindings for the system interpreter
SYSTEM_PYTHON = "/usr/bin/python3"


class Unavailable(Exception):
    """The bindings cannot be loaded: the message says what to install."""


@functools.lru_cache(maxsize=1)
def bindings() -> ModuleType:
    """babeltrace2's ``bt2`` module (Unavailable when it is not installed for this Python version)."""
    try:
        return importlib.import_module("bt2")
    except ImportError:
        pass
    where = _system_bt2()
    if where is None:
        raise Unavailable("babeltrace2's Python bindings are not installed (Debian: `apt-get install python3-bt2`, "
                          "or `scripts/install-tools`)")
    spec = importlib.util.spec_from_file_location("bt2", os.path.join(where, "__init__.py"),
                                                  submodule_search_locations=[where])
    if spec is None or spec.loader is None:
        raise Unavailable(f"babeltrace2's Python bindings in {where} cannot be loaded")
    module = importlib.util.module_from_spec(spec)
    sys.modules["bt2"] = module
    try:
        spec.loader.exec_module(module)
    except Exception as err:  # (a native module that does not load: any error of the import)
        del sys.modules["bt2"]
        raise Unavailable(f"babeltrace2's Python bindings in {where} do not load here: {err}") from None
    return module


def _system_bt2() -> str | None:
    """The ``bt2`` package of the system interpreter, if that is this Python's version."""
    if not os.path.exists(SYSTEM_PYTHON):
        return None
    probe = ("import sys, os, bt2; print('%d.%d' % sys.version_info[:2]); "
             "print(os.path.dirname(bt2.__file__))")
    try:
        done = subprocess.run([SYSTEM_PYTHON, "-c", probe], capture_output=True, text=True, timeout=30, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    lines = done.stdout.split()
    if done.returncode != 0 or len(lines) != 2 or lines[0] != "{}.{}".format(*sys.version_info[:2]):
        return None
    return lines[1]


# ------------------------------------------------------------------ the reader


@dataclass
class _Process:
    """What one process registered, by handle (handles are addresses: unique within a process)."""

    nodes: dict[int, str] = field(default_factory=dict)  # node handle -> "/ns/name"
    timers: dict[int, int] = field(default_factory=dict)  # timer handle -> period (ns)
    timer_nodes: dict[int, int] = field(default_factory=dict)  # timer handle -> node handle
    timer_callbacks: dict[int, int] = field(default_factory=dict)  # callback -> timer handle
    subscriptions: dict[int, tuple[int, str]] = field(default_factory=dict)  # rcl handle -> (node, topic)
    rmw_subscriptions: dict[int, int] = field(default_factory=dict)  # rmw handle -> rcl handle
    publishers: dict[int, tuple[int, str]] = field(default_factory=dict)  # rcl handle -> (node, topic)
    publishing: dict[int, tuple[str, str, int, int]] = field(default_factory=dict)  # thread -> (topic, node,
    # message, time) of its last publish still waiting for its source timestamp
    linked: dict[int, tuple[str, str] | None] = field(default_factory=dict)  # publisher -> (topic, node) of
    # a publisher whose messages are linked (None: not linked), as first published
    receiving: dict[int | None, tuple[str, str, tuple[int, int]] | None] = field(default_factory=dict)
    # rcl subscription -> (topic, node, key) of a subscription whose receipts are linked, as first received
    rclcpp_subscriptions: dict[int, int] = field(default_factory=dict)  # rclcpp subscription -> rcl handle
    subscription_callbacks: dict[int, int] = field(default_factory=dict)  # callback -> rclcpp subscription
    symbols: dict[int, str] = field(default_factory=dict)  # callback -> symbol
    registered: list[int] = field(default_factory=list)  # callbacks, in the order they were added
    open: dict[tuple[int, int], tuple[int, int]] = field(default_factory=dict)  # (callback, thread) -> (start,
    # last publish): a callback of a reentrant group may run on two threads at once
    running: dict[int, int] = field(default_factory=dict)  # thread -> callback running on it
    jobs: dict[int, Jobs] = field(default_factory=dict)  # callback -> its jobs
    intra_stamped: bool = False  # its intra-process publishes carry their message timestamp (CARET's)


class Reader:
    def __init__(self) -> None:
        self.processes: dict[int, _Process] = {}
        self.linker = Linker()
        self.intra_linker = Linker(intra=True)
        self.events = 0
        self.ignored: dict[str, int] = {}
        self.handlers: dict[str, Callable[..., None]] = {name: getattr(self, "on_" + name.split(":", 1)[1])
                                                         for name in USED}

    def process(self, pid: int) -> _Process:
        found = self.processes.get(pid)
        if found is None:
            found = self.processes[pid] = _Process()
        return found

    def ignore(self, name: str) -> None:
        key = name if name.startswith("ros2:") else "(events of other providers)"
        self.ignored[key] = self.ignored.get(key, 0) + 1

    # each handler: (process, time, thread, the event's fields in the order USED names them)

    def on_rcl_node_init(self, p: _Process, at: int, tid: int, node: int, name: str, ns: str) -> None:
        p.nodes[node] = (ns.rstrip("/") + "/" + name) if ns else "/" + name

    def on_rcl_timer_init(self, p: _Process, at: int, tid: int, timer: int, period: int) -> None:
        p.timers[timer] = period

    def on_rclcpp_timer_callback_added(self, p: _Process, at: int, tid: int, timer: int, callback: int) -> None:
        p.timer_callbacks[callback] = timer
        p.registered.append(callback)

    def on_rclcpp_timer_link_node(self, p: _Process, at: int, tid: int, timer: int, node: int) -> None:
        p.timer_nodes[timer] = node

    def on_rcl_publisher_init(self, p: _Process, at: int, tid: int, handle: int, node: int, topic: str) -> None:
        p.publishers[handle] = (node, topic)
        p.linked.pop(handle, None)  # (an address used again)

    def on_rcl_subscription_init(self, p: _Process, at: int, tid: int, handle: int, node: int, rmw: int,
                                 topic: str) -> None:
        p.subscriptions[handle] = (node, topic)
        p.rmw_subscriptions[rmw] = handle
        p.receiving.pop(handle, None)  # (an address used again)

    def on_rclcpp_subscription_init(self, p: _Process, at: int, tid: int, handle: int, subscription: int) -> None:
        p.rclcpp_subscriptions[subscription] = handle

    def on_rclcpp_subscription_callback_added(self, p: _Process, at: int, tid: int, subscription: int,
                                              callback: int) -> None:
        p.subscription_callbacks[callback] = subscription
        p.registered.append(callback)

    def on_rclcpp_callback_register(self, p: _Process, at: int, tid: int, callback: int, symbol: str) -> None:
        p.symbols[callback] = symbol

    def on_callback_start(self, p: _Process, at: int, tid: int, callback: int) -> None:
        p.open[(callback, tid)] = (at, at)
        p.running[tid] = callback

    def on_callback_end(self, p: _Process, at: int, tid: int, callback: int) -> None:
        started = p.open.pop((callback, tid), None)
        p.running.pop(tid, None)
        if started is None:
            return  # (its start was before the trace began)
        jobs = p.jobs.get(callback)
        if jobs is None:
            jobs = p.jobs[callback] = Jobs()
        start, wrote = started
        jobs.add(start, at, wrote if wrote > start else at)

    def on_rcl_publish(self, p: _Process, at: int, tid: int, publisher: int, message: int) -> None:
        linked = p.linked.get(publisher, _UNSEEN)
        if linked is _UNSEEN:
            linked = p.linked[publisher] = _linked_topic(p, publisher)
        if linked is not None:
            p.publishing[tid] = (linked[0], linked[1], message, at)
        elif p.publishing:
            p.publishing.pop(tid, None)
        _wrote(p, at, tid)

    def on_rclcpp_intra_publish(self, p: _Process, at: int, tid: int, publisher: int, message: int,
                                stamp: int | None) -> None:
        linked = p.linked.get(publisher, _UNSEEN)
        if linked is _UNSEEN:
            linked = p.linked[publisher] = _linked_topic(p, publisher)
        if stamp is not None:
            p.intra_stamped = True
        if linked is not None:
            self.intra_linker.published(linked[0], linked[1], (id(p), message, stamp), at)
        _wrote(p, at, tid)

    def on_dispatch_intra_process_subscription_callback(self, p: _Process, at: int, tid: int, callback: int,
                                                        message: int, stamp: int) -> None:
        subscription = p.subscription_callbacks.get(callback)
        handle = p.rclcpp_subscriptions.get(subscription) if subscription is not None else None
        linked = p.receiving.get(handle, _UNSEEN_SUBSCRIPTION)
        if linked is _UNSEEN_SUBSCRIPTION:
            linked = p.receiving[handle] = _linked_subscription(p, handle)
        if linked is not None:
            key = (id(p), message, stamp if p.intra_stamped else None)
            self.intra_linker.received_intra(linked[0], linked[1], key, at)

    def on_rmw_publish(self, p: _Process, at: int, tid: int, message: int, stamp: int) -> None:
        self._stamped(p, tid, message, stamp)

    def on_dds_bind_addr_to_stamp(self, p: _Process, at: int, tid: int, message: int, stamp: int) -> None:
        self._stamped(p, tid, message, stamp)

    def _stamped(self, p: _Process, tid: int, message: int, stamp: int) -> None:
        """The source timestamp of the message last published on thread ``tid``, if it is that message."""
        waiting = p.publishing.get(tid)
        if waiting is not None and waiting[2] == message:
            del p.publishing[tid]
            self.linker.published(waiting[0], waiting[1], stamp, waiting[3])

    def on_rmw_take(self, p: _Process, at: int, tid: int, rmw: int, stamp: int, taken: int) -> None:
        if taken:
            self._received(p, p.rmw_subscriptions.get(rmw), stamp, at)

    def on_dispatch_subscription_callback(self, p: _Process, at: int, tid: int, callback: int, stamp: int) -> None:
        subscription = p.subscription_callbacks.get(callback)
        self._received(p, p.rclcpp_subscriptions.get(subscription) if subscription is not None else None, stamp, at)

    def _received(self, p: _Process, handle: int | None, stamp: int, at: int) -> None:
        linked = p.receiving.get(handle, _UNSEEN_SUBSCRIPTION)
        if linked is _UNSEEN_SUBSCRIPTION:
            linked = p.receiving[handle] = _linked_subscription(p, handle)
        if linked is not None:
            self.linker.received(linked[0], linked[1], linked[2], stamp, at)

    # ------------------------------------------------------------ the result

    def recording(self, paths: tuple[str, ...]) -> Recording:
        out = Recording(paths, "lttng", events=self.events)
        out.ignored.update(self.ignored)
        rank = 0
        for pid in sorted(self.processes):
            p = self.processes[pid]
            alike: dict[tuple[object, ...], int] = {}
            subscribed: dict[int, str] = {}  # rcl subscription handle -> the key of its callback
            for callback in p.registered:
                found = _identify(p, callback, pid)
                if found is None:
                    continue
                handle = p.rclcpp_subscriptions.get(p.subscription_callbacks.get(callback, -1))
                first = subscribed.get(handle, "") if handle is not None else ""
                if first:  # (a subscription's intra-process waitable's callback: its jobs the subscription's)
                    out.jobs[first] = _in_start_order(_joined(out.jobs[first], p.jobs.get(callback) or Jobs()))
                    continue
                if handle is not None:
                    subscribed[handle] = found.key
                same = (found.node, found.kind, found.period_ns, found.topic, found.symbol)
                order = alike.get(same, 0)
                alike[same] = order + 1
                key = found.key
                out.callbacks[key] = Callback(key, found.node, found.kind, found.period_ns, found.topic, found.symbol,
                                              order, registered=rank)
                rank += 1
                out.jobs[key] = _in_start_order(p.jobs.get(callback) or Jobs())
            unfinished = sum(1 for c, _ in p.open
                             if c in p.jobs or c in p.timer_callbacks or c in p.subscription_callbacks)
            if unfinished:
                out.partial.append(f"{unfinished} job(s) of process {pid} started but did not end before the trace did "
                                   "(left out)")
        topics = {topic for p in self.processes.values() for _, topic in p.subscriptions.values()}
        self.linker.finish(out, topics)
        self.intra_linker.finish(out, topics)
        return out


def _wrote(p: _Process, at: int, tid: int) -> None:
    """A publish at ``at`` on thread ``tid``: the last output of the job running there (if one is)."""
    callback = p.running.get(tid)
    if callback is None:
        return
    started = p.open.get((callback, tid))
    if started is not None:
        p.open[(callback, tid)] = (started[0], at)


def _linked_topic(p: _Process, publisher: int) -> tuple[str, str] | None:
    """(topic, node) of a registered publisher whose messages are linked (None: unknown, or of a topic
    left out)."""
    topic = p.publishers.get(publisher)
    node = p.nodes.get(topic[0]) if topic is not None else None
    if topic is None or node is None or topic[1] in IGNORED_TOPICS:
        return None
    return topic[1], node


def _linked_subscription(p: _Process, handle: int | None) -> tuple[str, str, tuple[int, int]] | None:
    """(topic, node, key) of a registered subscription whose receipts are linked (None: unknown, or of
    a topic left out)."""
    found = p.subscriptions.get(handle) if handle is not None else None
    node = p.nodes.get(found[0]) if found is not None else None
    if handle is None or found is None or node is None or found[1] in IGNORED_TOPICS:
        return None
    return found[1], node, (id(p), handle)


def _joined(first: Jobs, second: Jobs) -> Jobs:
    """The jobs of both (in no particular order)."""
    out = Jobs()
    for jobs in (first, second):
        out.starts.extend(jobs.starts)
        out.ends.extend(jobs.ends)
        out.writes.extend(jobs.writes)
    return out


def _in_start_order(jobs: Jobs) -> Jobs:
    """The jobs in the order they started (they are recorded as they end: a callback running on two
    threads at once ends out of order)."""
    starts = jobs.starts
    if all(a <= b for a, b in zip(starts, starts[1:], strict=False)):
        return jobs
    order = sorted(range(len(jobs)), key=starts.__getitem__)
    out = Jobs()
    for k in order:
        out.add(jobs.starts[k], jobs.ends[k], jobs.writes[k])
    return out


def _identify(p: _Process, callback: int, pid: int) -> Callback | None:
    """A registered callback's identity (None: one of neither kind)."""
    key = f"{pid}:{callback:#x}"
    symbol = p.symbols.get(callback, "")
    if callback in p.timer_callbacks:
        timer = p.timer_callbacks[callback]
        node = p.nodes.get(p.timer_nodes.get(timer, -1))
        return Callback(key, node, "timer", p.timers.get(timer), None, symbol)
    if callback in p.subscription_callbacks:
        handle = p.rclcpp_subscriptions.get(p.subscription_callbacks[callback], -1)
        node_handle, topic = p.subscriptions.get(handle, (-1, None))
        return Callback(key, p.nodes.get(node_handle), "subscription", None, topic, symbol)
    return None
