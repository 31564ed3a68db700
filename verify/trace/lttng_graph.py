"""The babeltrace2 graph that reads LTTng traces for ``lttng.py``: one ``source.ctf.fs`` per trace
directory, ``filter.utils.muxer`` (time order across streams and traces), and a sink of our own.

The sink takes the messages in the batches the graph hands over and reads each event through the
bindings' native functions (``bt2._native_bt``: the functions babeltrace2's own Python classes call),
without building a Python object per message: the bindings' classes cost several microseconds a
message, too slow for traces of millions of events (benchmarks: ``trace-read``). What an event class
holds — its name, the positions of the fields a handler takes, the ``vpid``/``vtid`` context — is
looked up once per class.
"""
from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Sequence
from typing import Any

from .lttng_events import USED, Reader


class Failed(Exception):
    """The graph stopped before the end (a corrupt or truncated trace): ``reason`` in one line."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


def trace_directories(paths: Sequence[str]) -> list[str]:
    """The CTF traces under ``paths``: every directory holding a ``metadata`` file, in name order."""
    found = []
    for path in paths:
        for here, dirs, files in os.walk(path):
            dirs.sort()
            if "metadata" in files:
                found.append(here)
    return found


Getter = Callable[[Any], Any]


def _getters(nb: Any) -> dict[int, Getter]:
    return {nb.FIELD_CLASS_TYPE_UNSIGNED_INTEGER: nb.field_integer_unsigned_get_value,
            nb.FIELD_CLASS_TYPE_UNSIGNED_ENUMERATION: nb.field_integer_unsigned_get_value,
            nb.FIELD_CLASS_TYPE_SIGNED_INTEGER: nb.field_integer_signed_get_value,
            nb.FIELD_CLASS_TYPE_SIGNED_ENUMERATION: nb.field_integer_signed_get_value,
            nb.FIELD_CLASS_TYPE_STRING: nb.field_string_get_value}


def _members(nb: Any, structure: Any, getters: dict[int, Getter]) -> dict[str, tuple[int, Getter | None]]:
    """A structure field class's members: name → (index, how to read its value; None: not a number or text)."""
    if structure is None:
        return {}
    out = {}
    for k in range(nb.field_class_structure_get_member_count(structure)):
        member = nb.field_class_structure_borrow_member_by_index_const(structure, k)
        kind = nb.field_class_get_type(nb.field_class_structure_member_borrow_field_class_const(member))
        out[nb.field_class_structure_member_get_name(member)] = (k, getters.get(kind))
    return out


class _Classes:
    """What each event class holds, looked up once: (handler or None, name, payload fields, pid, tid)."""

    def __init__(self, nb: Any, reader: Reader):
        self.nb, self.reader, self.getters = nb, reader, _getters(nb)
        self.known: dict[int, tuple[Any, ...]] = {}

    def of(self, cls: Any) -> tuple[Any, ...]:
        key = int(cls)
        found = self.known.get(key)
        if found is None:
            found = self.known[key] = self._describe(cls)
        return found

    def _describe(self, cls: Any) -> tuple[Any, ...]:
        nb = self.nb
        name = nb.event_class_get_name(cls) or "(unnamed)"
        stream_class = nb.event_class_borrow_stream_class_const(cls)
        context = _members(nb, nb.stream_class_borrow_event_common_context_field_class_const(stream_class),
                           self.getters)
        wanted = USED.get(name)
        handler = self.reader.handlers.get(name)
        payload = _members(nb, nb.event_class_borrow_payload_field_class_const(cls), self.getters)
        fields = tuple(payload_member(payload, f) for f in wanted or ())
        if wanted is None or any(g is None for _, g in fields) \
                or nb.stream_class_borrow_default_clock_class_const(stream_class) is None:
            name = name if wanted is None else f"{name} (without ros2_tracing's fields or a clock)"
            return (None, name, (), None, None)
        pid = context.get("vpid", (0, None))
        tid = context.get("vtid", (0, None))
        return (handler, name, fields, pid if pid[1] else None, tid if tid[1] else None)


def payload_member(payload: dict[str, tuple[int, Getter | None]],
                   wanted: str) -> tuple[int, Getter | None]:
    """The payload member ``wanted`` names (``"a|b"``: the first of them the event has; ``"?a"``: None
    when the event has no ``a``)."""
    if wanted.startswith("?"):
        return payload.get(wanted[1:], (0, _absent))
    return next((payload[name] for name in wanted.split("|") if name in payload), (0, None))


def _absent(field: Any) -> None:
    """The value of an optional field the event does not have."""
    return None


def run(traces: Sequence[str], reader: Reader) -> None:
    """Feed every event of ``traces``, in time order, to ``reader`` (Failed when the graph stops early)."""
    from .lttng_events import bindings

    bt2 = bindings()
    nb = importlib.import_module("bt2._native_bt")
    classes = _Classes(nb, reader)
    sink_class = _sink_class(bt2, _consumer(nb, classes, reader, bt2.Stop))
    try:
        graph = bt2.Graph()
        ctf = bt2.find_plugin("ctf").source_component_classes["fs"]
        muxer = graph.add_component(bt2.find_plugin("utils").filter_component_classes["muxer"], "muxer")
        k = 0
        for n, trace in enumerate(traces):
            source = graph.add_component(ctf, f"source{n}", {"inputs": [trace]})
            for port in source.output_ports.values():
                graph.connect_ports(port, muxer.input_ports[f"in{k}"])
                k += 1
        sink = graph.add_component(sink_class, "sink")
        graph.connect_ports(muxer.output_ports["out"], sink.input_ports["in"])
        graph.run()
    except bt2._Error as err:
        raise Failed(_gist(err)) from None


def _sink_class(bt2: Any, consume: Callable[[Any], None]) -> Any:
    """A babeltrace2 sink component class whose every ``consume`` hands a batch of messages to ``consume``
    (made by the bindings' own metaclass, as a ``class`` statement would)."""
    base = bt2._UserSinkComponent

    def __init__(self: Any, config: Any, params: Any, obj: Any) -> None:
        self._port = self._add_input_port("in")

    def _user_graph_is_configured(self: Any) -> None:
        self._it = self._create_message_iterator(self._port)

    def _user_consume(self: Any) -> None:
        consume(self._it._ptr)

    return type(base)("Sink", (base,), {"__init__": __init__, "_user_graph_is_configured": _user_graph_is_configured,
                                        "_user_consume": _user_consume, "__module__": __name__})


def _consumer(nb: Any, classes: _Classes, reader: Reader, stop: type[Exception]) -> Callable[[Any], None]:
    get_range = nb.bt2_self_component_port_input_get_msg_range
    end, again, ok = (getattr(nb, "__BT_FUNC_STATUS_" + s) for s in ("END", "AGAIN", "OK"))
    message_type, event_type = nb.message_get_type, nb.MESSAGE_TYPE_EVENT
    borrow_event, borrow_class = nb.message_event_borrow_event_const, nb.event_borrow_class_const
    clock, ns_from_origin = nb.message_event_borrow_default_clock_snapshot_const, nb.clock_snapshot_get_ns_from_origin
    payload_of, context_of = nb.event_borrow_payload_field_const, nb.event_borrow_common_context_field_const
    member, put = nb.field_structure_borrow_member_field_by_index_const, nb.message_put_ref
    process, processes, ignore, known = reader.process, reader.processes, reader.ignore, classes.known

    def consume(iterator: Any) -> None:
        status, messages = get_range(iterator)
        if status == end:
            raise stop
        if status == again:
            return
        if status != ok:
            raise Failed(f"babeltrace2 stopped with status {status}")
        count = 0
        try:
            for m in messages:
                if message_type(m) != event_type:
                    continue
                event = borrow_event(m)
                cls = borrow_class(event)
                handler, name, fields, pid, tid = known.get(int(cls)) or classes.of(cls)
                count += 1
                if handler is None:
                    ignore(name)
                    continue
                _, at = ns_from_origin(clock(m))
                payload = payload_of(event)
                context = context_of(event) if pid is not None or tid is not None else None
                p = pid[1](member(context, pid[0])) if pid is not None else 0
                t = tid[1](member(context, tid[0])) if tid is not None else 0
                q = processes.get(p) or process(p)
                if len(fields) == 1:  # (callback_start, callback_end: most events)
                    (i, g), = fields
                    handler(q, at, t, g(member(payload, i)))
                elif len(fields) == 2:  # (rcl_publish, rmw_publish, a dispatch)
                    (i, g), (j, h) = fields
                    handler(q, at, t, g(member(payload, i)), h(member(payload, j)))
                elif len(fields) == 3:  # (rmw_take, the intra-process events)
                    (i, g), (j, h), (k, f) = fields
                    handler(q, at, t, g(member(payload, i)), h(member(payload, j)), f(member(payload, k)))
                else:
                    handler(q, at, t, *[g(member(payload, i)) for i, g in fields])
        finally:
            reader.events += count
            for m in messages:
                put(m)

    return consume


def _gist(err: BaseException) -> str:
    """babeltrace2's error in one line: its deepest cause's message."""
    lines = [ln.strip() for ln in str(err).splitlines() if ln.strip()]
    useful = [ln for ln in lines if not ln.startswith(("File ", "Traceback", "ERROR:", "CAUSED BY"))]
    return ((useful or lines or [type(err).__name__])[-1])[:300]
