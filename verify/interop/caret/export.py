"""A configured system's chains as CARET named paths (specs/interop.md, "CARET").

With ``--from`` (the architecture file the system was imported from) the file is written back with
only its ``named_paths`` replaced by the system's chains, in the file's own node and topic names;
everything else in it stays as it was. Without it, a whole architecture file is written from the
model: every instance a node, every task a callback, every connected out-port a topic
``/INSTANCE/PORT``, every executor an executor — in CARET's own layout, so that
``Architecture('yaml', …)`` reads it and a user can measure on the robot what was analysed.
What CARET cannot hold exactly is reported (E707); a chain CARET cannot follow is refused (E706).
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Protocol

import yaml

from ...core.diagnostics import DiagnosticSink
from ...model.system import ChainModel, SystemModel, TaskModel
from ...core.source import Span
from .read import UNDEFINED, Architecture

#: our executor kinds as CARET's executor types
TYPES = {"single_threaded": "single_threaded_executor", "static_single_threaded": "static_single_threaded_executor",
         "events": "single_threaded_executor", "multi_threaded": "multi_threaded_executor"}


@dataclass
class Exported:
    files: dict[str, str]  # file name -> text


def dump(document: dict[str, Any]) -> str:
    """YAML as ``caret_analyze``'s exporter writes it."""
    return str(yaml.dump(document, indent=2, default_flow_style=False, sort_keys=False, allow_unicode=True))


def export_system(model: SystemModel, origin: list[Architecture] | None, origin_text: dict[str, str],
                  sink: DiagnosticSink) -> Exported | None:
    """The architecture file of a configured system (file name -> text), or None after an E706."""
    if origin:
        arch = origin[0]
        names = _origin_names(arch)
        paths = [p for c in model.chains if (p := _named_path(model, c, names, sink)) is not None]
        if any(d.code == "E706" for d in sink.items):
            return None
        text = replace_named_paths(origin_text[arch.path], paths)
        return Exported({os.path.basename(arch.path): text})
    generated = _Generated()
    paths = [p for c in model.chains if (p := _named_path(model, c, generated, sink)) is not None]
    if any(d.code == "E706" for d in sink.items):
        return None
    sink.emit("E707", f"system `{model.name}` is written as a whole new architecture file: its callbacks' symbols "
              "are placeholders (`verify:INSTANCE.TASK`), which match no callback CARET traces", model.span,
              "no original architecture file", help="pass `--from ARCHITECTURE.yaml`, the file the system was "
              "imported from, to keep CARET's own nodes, symbols and topics and replace only its named paths")
    document = {"named_paths": paths, "executors": _executors(model, sink), "nodes": _nodes(model, generated, sink)}
    return Exported({"architecture.yaml": dump(document)})


def replace_named_paths(text: str, paths: list[dict[str, Any]]) -> str:
    """``text`` with its top-level ``named_paths`` block replaced by ``paths`` (the other lines kept)."""
    lines = text.splitlines(keepends=True)
    start = next((k for k, ln in enumerate(lines) if re.match(r"named_paths\s*:", ln)), None)
    block = dump({"named_paths": paths})
    if start is None:
        return block + text
    end = start + 1
    while end < len(lines) and (lines[end].startswith((" ", "-", "\t", "#")) or not lines[end].strip()):
        end += 1
    return "".join(lines[:start]) + block + "".join(lines[end:])


# ------------------------------------------------------------------ names


class _Names(Protocol):
    """The node of an instance and the topic of an out-port (instance, port)."""

    def node(self, instance: str) -> str: ...

    def topic(self, instance: str, port: str) -> str | None: ...


class _Generated:
    """The names of a whole architecture written from the model: ``/INSTANCE``, ``/INSTANCE/PORT``."""

    def node(self, instance: str) -> str:
        return f"/{instance}"

    def topic(self, instance: str, port: str) -> str | None:
        return f"/{instance}/{port}"


class _Origin:
    """The names of the --from file, as its import gave them."""

    def __init__(self, nodes: dict[str, str], topics: dict[tuple[str, str], str]):
        self.nodes, self.topics = nodes, topics

    def node(self, instance: str) -> str:
        return self.nodes.get(instance, f"/{instance}")

    def topic(self, instance: str, port: str) -> str | None:
        return self.topics.get((instance, port))


def _origin_names(arch: Architecture) -> _Origin:
    """The names the import gave the file's nodes and topics, backwards (the import is deterministic)."""
    from .to_vfy import imported_names

    return _Origin(*imported_names(arch))


# ------------------------------------------------------------------ named paths


def _named_path(model: SystemModel, chain: ChainModel, names: _Names, sink: DiagnosticSink) -> dict[str, Any] | None:
    """The named path of ``chain``: one entry per node it passes, with the topics between them."""
    entries: list[dict[str, str]] = []
    instance = model.task(chain.tasks[0]).instance
    subscribe: str = UNDEFINED
    for hop in chain.hops:
        source_instance, port = hop.link.source.split(".", 1)
        reader = model.task(hop.reader).instance
        if reader == instance:  # (a hop inside the node: its callbacks pass the value)
            continue
        topic = names.topic(source_instance, port)
        if topic is None:
            sink.emit("E706", f"chain `{chain.name}` passes `{hop.link.source}`, which is no topic of the --from "
                      "architecture file", chain.span, "no CARET topic",
                      help="export without --from, or chain through the imported topics")
            return None
        entries.append({"node_name": names.node(instance), "publish_topic_name": topic,
                        "subscribe_topic_name": subscribe})
        instance, subscribe = reader, topic
    entries.append({"node_name": names.node(instance), "publish_topic_name": UNDEFINED,
                    "subscribe_topic_name": subscribe})
    if len(entries) < 2:
        sink.emit("E707", f"chain `{chain.name}` stays in node `{instance}`: a CARET path passes topics between "
                  "nodes, so it is not exported", chain.span, "not a CARET path",
                  help="CARET measures a node alone by its callbacks' latencies")
        return None
    return {"path_name": chain.name, "node_chain": entries}


# ------------------------------------------------------------------ the whole architecture


def _ns(value: Fraction, what: str, where: Span, sink: DiagnosticSink) -> int:
    ns = value * 10**9
    if ns.denominator != 1:
        sink.emit("E707", f"{what} is not a whole number of nanoseconds: written as {round(ns)} ns", where,
                  "rounded", help="CARET holds periods in nanoseconds")
    return round(ns)


def _executors(model: SystemModel, sink: DiagnosticSink) -> list[dict[str, Any]]:
    out = []
    for ex in model.executors:
        if ex.kind == "events":
            sink.emit("E707", f"executor `{ex.name}` is an events executor, which CARET's architecture file has no "
                      "type for: written as a single-threaded executor", ex.span, "approximated",
                      help="CARET groups callbacks by executor; its measurements do not depend on the type")
        groups = sorted({_group(model, t)[0] for t in model.callbacks(ex.name)})
        out.append({"executor_type": TYPES[ex.kind], "executor_name": ex.name, "callback_group_names": groups})
    plain = [t for t in model.tasks if t.executor is None]
    if plain:
        sink.emit("E707", "tasks with a priority run as threads, which CARET has no term for: each node's are written "
                  "as one single-threaded executor `thread_NODE`", plain[0].span, "approximated",
                  help="CARET groups callbacks by executor; its measurements do not depend on the grouping")
    for inst in dict.fromkeys(t.instance for t in plain):
        out.append({"executor_type": "single_threaded_executor", "executor_name": f"thread_{inst}",
                    "callback_group_names": [f"/{inst}/threads"]})
    return sorted(out, key=lambda e: e["executor_name"])


def _group(model: SystemModel, task: TaskModel) -> tuple[str, str]:
    """The CARET name and type of a task's callback group: a declared group by its name, a default group
    by its executor's, a task with a priority in its node's ``threads``."""
    if task.executor is None or task.group is None:
        return f"/{task.instance}/threads", "mutually_exclusive"
    group = model.group(task.group)
    return f"/{task.instance}/{group.name or task.executor}", group.kind


def _nodes(model: SystemModel, names: _Names, sink: DiagnosticSink) -> list[dict[str, Any]]:
    told: set[str] = set()
    return sorted((_NodeWriter(model, names, inst.name, sink, told).node() for inst in model.instances),
                  key=lambda n: n["node_name"])


class _NodeWriter:
    """One instance as a CARET node: its callbacks, storing callbacks, passings, topics and groups."""

    def __init__(self, model: SystemModel, names: _Names, instance: str, sink: DiagnosticSink, told: set[str]):
        self.model, self.names, self.instance, self.sink, self.told = model, names, instance, sink, told
        self.name = f"/{instance}"
        self.tasks = [model.task(t) for t in model.instance(instance).tasks]
        self.callbacks: list[dict[str, Any]] = []
        self.passings: list[dict[str, str]] = []
        self.subscribes: list[dict[str, str]] = []
        self.stores: dict[str, str] = {}  # in-port -> the callback storing its messages

    def topic_of(self, port: str) -> str | None:
        link = self.model.link_into(f"{self.instance}.{port}")
        return None if link is None else self.names.topic(*link.source.split(".", 1))

    def store(self, port: str) -> str | None:
        """The callback whose value a reader of ``port`` reads: the writer itself for a connection inside
        the node (a variable passing), else a subscription callback keeping the latest message."""
        link = self.model.link_into(f"{self.instance}.{port}")
        if link is not None and link.source.split(".", 1)[0] == self.instance:
            return f"{self.name}/{self.model.task(link.writer).name}"
        topic = self.topic_of(port)
        if topic is None:
            return None
        if port not in self.stores:
            self.stores[port] = f"{self.name}/store_{port}"
            self.callbacks.append({"callback_name": self.stores[port], "callback_type": "subscription_callback",
                                   "topic_name": topic, "symbol": f"verify:{self.instance}.store_{port}"})
            self.subscribes.append({"topic_name": topic, "callback_name": self.stores[port]})
        return self.stores[port]

    def tell(self, key: str, task: TaskModel, message: str, help: str) -> None:
        if key not in self.told:
            self.told.add(key)
            self.sink.emit("E707", message, task.span, "approximated", help=help)

    def callback(self, t: TaskModel) -> None:
        name = f"{self.name}/{t.name}"
        act = t.activation
        entry: dict[str, Any] = {"callback_name": name}
        triggered: list[str] = []
        period = act.strict_period
        if period is not None:
            entry["callback_type"] = "timer_callback"
            entry["period_ns"] = _ns(period, f"the period of `{t.id}`", t.span, self.sink)
        else:
            entry["callback_type"] = "subscription_callback"
            members = list(act.trigger_members) if act.trigger_port is not None else []
            connected = [(m, tp) for m in members if (tp := self.topic_of(m)) is not None]
            if not connected:
                entry["topic_name"] = f"{name}/events"
                self.tell("sporadic", t, f"`{t.id}` is activated from outside the system: written as a subscription "
                          "to a topic no node publishes", "rename the topic to the one that drives it on the robot")
            else:
                entry["topic_name"] = connected[0][1]
                self.subscribes.append({"topic_name": connected[0][1], "callback_name": name})
                triggered = [m for m, _tp in connected]
                if len(connected) > 1:
                    self.tell("compound", t, f"`{t.id}` fires on several ports: written as a subscription callback "
                              "of its first port and one storing callback per other port",
                              "CARET follows the stored messages by variable passings")
                for m, _tp in connected[1:]:
                    self.pass_from(self.store(m), name)
        entry["symbol"] = f"verify:{t.id}"
        self.callbacks.append(entry)
        for r in t.reads:
            if r.port not in triggered:
                self.pass_from(self.store(r.port), name)

    def pass_from(self, writer: str | None, reader: str) -> None:
        if writer is not None:
            self.passings.append({"callback_name_write": writer, "callback_name_read": reader})

    def publishes(self) -> list[dict[str, Any]]:
        out = []
        for port in self.model.instance(self.instance).ports:
            pname = port.split(".", 1)[1]
            if self.model.port(port).direction != "out" or all(lk.target.split(".", 1)[0] == self.instance
                                                              for lk in self.model.links_from(port)):
                continue  # (no topic: unconnected, or a variable passing inside the node)
            writer = self.model.producer(port)
            out.append({"topic_name": self.names.topic(self.instance, pname),
                        "callback_names": [f"{self.name}/{self.model.task(writer).name}"] if writer else [UNDEFINED]})
        return sorted(out, key=lambda p: p["topic_name"])

    def groups(self) -> dict[tuple[str, str], list[str]]:
        """(name, type) -> callbacks."""
        groups: dict[tuple[str, str], list[str]] = {}
        for t in self.tasks:
            groups.setdefault(_group(self.model, t), []).append(f"{self.name}/{t.name}")
        for port, keeper in self.stores.items():  # (a storing callback runs where its reader does)
            reader = next(t for t in self.tasks if any(r.port == port for r in t.reads)
                          or port in t.activation.trigger_members)
            groups[_group(self.model, reader)].append(keeper)
        return groups

    def node(self) -> dict[str, Any]:
        for t in self.tasks:
            self.callback(t)
        entry: dict[str, Any] = {
            "node_name": self.name,
            "callback_groups": [{"callback_group_type": kind, "callback_group_name": g,
                                 "callback_names": sorted(cbs)} for (g, kind), cbs in self.groups().items()],
        }
        if self.callbacks:
            entry["callbacks"] = sorted(self.callbacks, key=lambda c: c["callback_name"])
        if self.passings:
            entry["variable_passings"] = self.passings
        publishes = self.publishes()
        if publishes:
            entry["publishes"] = publishes
        if self.subscribes:
            entry["subscribes"] = sorted(self.subscribes, key=lambda s: s["topic_name"])
        return entry
