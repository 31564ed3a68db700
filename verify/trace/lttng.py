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
import multiprocessing
import os
from collections.abc import Iterable
from multiprocessing.connection import Connection
from .recording import Recording

from .lttng_events import Reader, bindings
from .lttng_events import Unavailable as Unavailable


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
