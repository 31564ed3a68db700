"""LTTng (CTF) traces as ros2_tracing and CARET record them, read with babeltrace2's Python bindings
(specs/trace.md §1.1).

The bindings are Debian's ``python3-bt2``, built for the system Python: ``bindings()`` imports them as
they are, or from the system interpreter's packages when that interpreter is the same Python version
as this one (only the ``bt2`` package is loaded from there). No CTF is parsed here.

The reader streams: every event is seen once, in time order across the traces given, and only what
the model can use is kept — the registrations of nodes, timers, subscriptions and callbacks (a few per
callback) and three numbers per job (start, end, last publish). Events of the ``ros2`` provider that
play no part are counted by name; events of other providers are counted as such.
"""
from __future__ import annotations

import functools
import importlib.util
import multiprocessing
import os
import subprocess
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from types import ModuleType

from .recording import Callback, Jobs, Recording

#: the events read, with the fields each handler takes (ros2_tracing's names; CARET records the same)
USED: dict[str, tuple[str, ...]] = {
    "ros2:rcl_node_init": ("node_handle", "node_name", "namespace"),
    "ros2:rcl_timer_init": ("timer_handle", "period"),
    "ros2:rclcpp_timer_callback_added": ("timer_handle", "callback"),
    "ros2:rclcpp_timer_link_node": ("timer_handle", "node_handle"),
    "ros2:rcl_subscription_init": ("subscription_handle", "node_handle", "topic_name"),
    "ros2:rclcpp_subscription_init": ("subscription_handle", "subscription"),
    "ros2:rclcpp_subscription_callback_added": ("subscription", "callback"),
    "ros2:rclcpp_callback_register": ("callback", "symbol"),
    "ros2:callback_start": ("callback",),
    "ros2:callback_end": ("callback",),
    "ros2:rcl_publish": ("publisher_handle",),
}
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
    rclcpp_subscriptions: dict[int, int] = field(default_factory=dict)  # rclcpp subscription -> rcl handle
    subscription_callbacks: dict[int, int] = field(default_factory=dict)  # callback -> rclcpp subscription
    symbols: dict[int, str] = field(default_factory=dict)  # callback -> symbol
    registered: list[int] = field(default_factory=list)  # callbacks, in the order they were added
    open: dict[tuple[int, int], tuple[int, int]] = field(default_factory=dict)  # (callback, thread) -> (start,
    # last publish): a callback of a reentrant group may run on two threads at once
    running: dict[int, int] = field(default_factory=dict)  # thread -> callback running on it
    jobs: dict[int, Jobs] = field(default_factory=dict)  # callback -> its jobs


class Reader:
    def __init__(self) -> None:
        self.processes: dict[int, _Process] = {}
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

    def on_rcl_subscription_init(self, p: _Process, at: int, tid: int, handle: int, node: int, topic: str) -> None:
        p.subscriptions[handle] = (node, topic)

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

    def on_rcl_publish(self, p: _Process, at: int, tid: int, publisher: int) -> None:
        callback = p.running.get(tid)
        if callback is None:
            return
        started = p.open.get((callback, tid))
        if started is not None:
            p.open[(callback, tid)] = (started[0], at)

    # ------------------------------------------------------------ the result

    def recording(self, paths: tuple[str, ...]) -> Recording:
        out = Recording(paths, "lttng", events=self.events)
        out.ignored.update(self.ignored)
        rank = 0
        for pid in sorted(self.processes):
            p = self.processes[pid]
            alike: dict[tuple[object, ...], int] = {}
            for callback in p.registered:
                found = _identify(p, callback, pid)
                if found is None:
                    continue
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


class Unreadable(Exception):
    """A trace that cannot be read at all (not CTF, no such directory): the message says why."""


def read(paths: Iterable[str]) -> Recording:
    """The recording of the LTTng traces under ``paths`` (directories), merged in time order. A trace
    that breaks off (truncated, corrupt) gives what was read before, with ``partial`` saying so;
    Unreadable when nothing can be read; Unavailable without the bindings.

    babeltrace2 aborts its process on some corrupt traces, so the reading runs in a child process
    (forked: nothing is imported again) that sends the recording back; a child that dies is a trace
    that cannot be read."""
    bindings()
    given = tuple(paths)
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_read_in_child, args=(given, send), daemon=True)
    child.start()
    send.close()
    try:
        outcome = receive.recv()
    except EOFError:
        outcome = None
    child.join()
    if outcome is None:
        raise Unreadable(f"babeltrace2 stopped reading it (its process ended with status {child.exitcode}): "
                         "the trace is corrupt")
    if isinstance(outcome, Exception):
        raise outcome
    assert isinstance(outcome, Recording)
    return outcome


def _read_in_child(given: tuple[str, ...], send: Connection) -> None:
    quiet = os.open(os.devnull, os.O_WRONLY)
    os.dup2(quiet, 2)  # (babeltrace2's own complaints, and an abort's, are not the user's to read)
    try:
        send.send(_read(given))
    except (Unreadable, Unavailable) as err:
        send.send(err)
    finally:
        send.close()


def _read(given: tuple[str, ...]) -> Recording:
    bindings()
    from . import lttng_graph

    reader = Reader()
    traces = lttng_graph.trace_directories(given)
    if not traces:
        raise Unreadable("no LTTng trace under it (no `metadata` file)")
    try:
        lttng_graph.run(traces, reader)
        stopped = None
    except lttng_graph.Failed as err:
        stopped = err.reason
    out = reader.recording(given)
    if stopped is not None:
        if reader.events == 0:
            raise Unreadable(stopped)
        out.partial.insert(0, f"the trace breaks off after {reader.events:,} events: {stopped}")
    return out


def _first_line(err: BaseException) -> str:
    """The gist of a babeltrace2 error (its first cause's message, one line)."""
    lines = [ln.strip() for ln in str(err).splitlines() if ln.strip()]
    useful = [ln for ln in lines if not ln.startswith(("File ", "Traceback"))]
    text = (useful or lines or [type(err).__name__])[-1]
    return text[:300]
