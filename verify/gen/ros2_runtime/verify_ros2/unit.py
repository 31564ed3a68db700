"""One process of a generated system (specs/codegen.md §2–§5): an executor of the model, a preemptive
task, or an instance's cooperative tasks. It subscribes the in-ports its tasks read, publishes the
out-ports they write, releases jobs as the model's activations say, runs them on one thread in the
order of its policy (``dispatch``), monitors the chains that end in it, and at shutdown writes its
monitors' summary and its job records.

    python -m PACKAGE.main UNIT --ros-args --params-file config/parameters.yaml -r __ns:=/SYSTEM
"""
from __future__ import annotations

import contextlib
import importlib
import json
import os
import signal
import sys
import threading
import time
from types import ModuleType
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.signals import SignalHandlerOptions

from .component import Input, Output
from .dispatch import Callback, Dispatcher, Job, Timer, Timers
from .monitor import ChainMonitor, Stamp, Violation
from .params import ConfigError, TaskConfig, nested, ns, task_config
from .wire import Pairing, Record, digest, from_wire, message_class, to_wire

WIRE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE)
READY_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
CONNECT_TIMEOUT_S = 30.0
#: how long the middleware may take to shut down once the results are written (§4)
SHUTDOWN_TIMEOUT_S = 10.0
START_MARGIN_NS = 200_000_000
MIDDLEWARE_PRIORITY = 97
TIMER_PRIORITY = 98
#: how long a thread holds the interpreter lock while another waits for it (Python's default: 5 ms): an
#: arrival or a timer release waits at most this long for a running job (specs/codegen.md §9)
SWITCH_INTERVAL_S = 0.0002


def now() -> int:
    return time.time_ns()


def realtime(cpu: int | None, priority: int, logger: Any, what: str) -> None:
    """Pin the calling thread to ``cpu`` and give it SCHED_FIFO ``priority``; a warning where the OS refuses."""
    try:
        if cpu is not None:
            os.sched_setaffinity(0, {cpu})
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except OSError as err:
        logger.warning(f"{what}: no real-time scheduling (CPU {cpu}, SCHED_FIFO {priority}): {err}; "
                       "the analysis' bounds do not apply")


def middleware_executor() -> Any:
    """What takes arrivals from the middleware: rclpy's single-threaded executor, whose thread waits
    in the middleware while nothing arrives (rclpy's experimental events executor polls, which at a
    real-time priority takes a whole CPU). The order of jobs is never the executor's (``dispatch``)."""
    return SingleThreadedExecutor()


class Register:
    """An in-port's register: the value that arrived last (keep-last, depth 1) and its record."""

    def __init__(self) -> None:
        self.value: Any = None
        self.present = False
        self.record: Record | None = None
        self.arrivals = 0


class Unit:
    def __init__(self, system: ModuleType, name: str) -> None:
        self.system = system
        self.name = name
        spec = system.UNITS[name]
        # (no parameter services: each is one more entity rclpy's executor walks at every arrival)
        self.node = Node(name, namespace="/" + system.NAMESPACE, start_parameter_services=False,
                         automatically_declare_parameters_from_overrides=True)
        self.log = self.node.get_logger()
        flat = {k: p.value for k, p in self.node.get_parameters_by_prefix("").items()}
        self.config = nested(flat)
        verify = self.config.get("verify", {})
        self.monitoring = bool(verify.get("monitor", True))
        self.run_id = str(verify.get("run", ""))
        self.summary_dir = str(verify.get("summary_dir", ""))
        self.trace_dir = str(verify.get("trace_dir", ""))
        self.rt = bool(verify.get("realtime", True))
        self.duration = float(verify.get("duration", 0.0))  # s after the agreed start (0: until stopped)
        self.tasks: dict[str, TaskConfig] = {}
        for task in spec["tasks"]:
            inst, t = task.split(".")
            self.tasks[task] = task_config(task, self.config.get("tasks", {}).get(inst, {}).get(t, {}))
        self.lock = threading.Lock()
        self.objects: dict[str, Any] = {}
        self.registers: dict[str, Register] = {}
        self.pairings: dict[str, Pairing] = {}
        self.publishers: dict[str, tuple[Any, Any, bool]] = {}
        self.subscriptions: dict[str, tuple[Any, Any]] = {}
        self.indices: dict[str, int] = {}
        self.counters: dict[str, int] = {t: 0 for t in self.tasks}
        self.fresh: dict[str, set[str]] = {}
        self.first_start: dict[str, int] = {}
        self.last_release: dict[str, int] = {}
        self.records: list[dict[str, Any]] = []
        self.monitors = self._monitors()
        self.violations_pub = self.node.create_publisher(message_class(None), "/verify/violations", WIRE_QOS)
        self.record_node = Node(name + "_records", namespace="/" + system.NAMESPACE, start_parameter_services=False,
                                enable_rosout=False)
        self._instances()
        self._ports()
        callbacks = {t: Callback(c.priority, c.activation == "timer", system.TASKS[t]["order"])
                     for t, c in self.tasks.items()}
        self.dispatcher = Dispatcher(spec["policy"], callbacks, self._run)
        self.timers = Timers([Timer(t, c.period, c.phase) for t, c in self.tasks.items() if c.activation == "timer"],
                             self._release, self._timer_scheduling)
        self._sporadic()
        self.stopping = threading.Event()
        self.started = threading.Event()

    # ---------------------------------------------------------------- set-up

    def _monitors(self) -> dict[str, ChainMonitor]:
        monitors = {}
        for chain, bounds in sorted(self.config.get("monitors", {}).items()):
            where = f"monitors.{chain}"
            monitors[chain] = ChainMonitor(chain, *(int(ns(bounds, k, where)) if k in bounds else 0
                                                    for k in ("reaction_time_ns", "data_age_ns", "jitter_ns")))
        if not self.monitoring:
            return {}
        if monitors and self.summary_dir:
            try:
                os.makedirs(self.summary_dir, exist_ok=True)
                probe = os.path.join(self.summary_dir, f".{self.name}.probe")
                with open(probe, "w", encoding="utf-8"):
                    pass
                os.remove(probe)
            except OSError as err:
                raise ConfigError(f"summary_dir {self.summary_dir!r} cannot be made or written: {err}") from err
        return monitors

    def _instances(self) -> None:
        for inst in sorted({t.split(".")[0] for t in self.tasks}):
            module, cls = self.system.INSTANCES[inst]
            self.objects[inst] = getattr(importlib.import_module(module), cls)(inst, self.node, self._by_hand(inst))

    def _by_hand(self, inst: str) -> Any:
        def release(task: str) -> None:
            self._sporadic_release(f"{inst}.{task}")
        return release

    def _read_ports(self) -> list[str]:
        """The in-ports ("instance.port") of the instances whose tasks the process runs."""
        return [f"{inst}.{p}" for inst in self.objects for p in self.system.IN_PORTS.get(inst, [])]

    def _ports(self) -> None:
        for port in self._read_ports():
            self.registers[port] = Register()
            info = self.system.PORTS[port]
            if not info["topic"]:
                continue
            pairing = self.pairings[port] = Pairing()
            records = self.record_node.create_subscription(message_class(None), info["topic"] + "/verify",
                                                           lambda m, p=pairing: self._record(p, m), WIRE_QOS)
            values = self.node.create_subscription(message_class(info["type"]), info["topic"],
                                                   lambda data, p=port: self._arrival(p, data), WIRE_QOS, raw=True)
            self.subscriptions[port] = (values, records)
        for task in self.tasks:
            inst = task.split(".")[0]
            for out in self.system.TASKS[task]["produces"]:
                info = self.system.PORTS[f"{inst}.{out}"]
                cls = message_class(info["type"])
                self.publishers[f"{inst}.{out}"] = (self.node.create_publisher(cls, info["topic"], WIRE_QOS),
                                                    self.node.create_publisher(message_class(None),
                                                                               info["topic"] + "/verify", WIRE_QOS),
                                                    info["type"] is not None)
                self.indices[f"{inst}.{out}"] = 0

    def _sporadic(self) -> None:
        empty = importlib.import_module("std_msgs.msg").Empty
        for task, cfg in self.tasks.items():
            if cfg.activation == "sporadic":
                topic = self.system.TASKS[task]["release_topic"]
                self.node.create_subscription(empty, topic, lambda _m, t=task: self._sporadic_release(t), WIRE_QOS)

    # ---------------------------------------------------------------- arrivals and releases

    def _record(self, pairing: Pairing, message: Any) -> None:
        try:
            pairing.add(Record.decode(message.data))
        except (ValueError, KeyError, TypeError) as err:
            self.log.warning(f"a record that is not one was dropped: {err}", throttle_duration_sec=1.0)

    def _arrival(self, port: str, data: bytes) -> None:
        info = self.system.PORTS[port]
        pairing = self.pairings[port]
        try:
            message = deserialize_message(data, message_class(info["type"]))
            value = from_wire(message, info["type"] is not None)
            key = digest(serialize_message(message))  # (as the writer serialized it: the wire may pad it)
        except Exception as err:  # (anything a foreign publisher may send)
            self.log.warning(f"a message on {info['topic']} that is not a {info['type']} was dropped: {err}",
                             throttle_duration_sec=1.0)
            return
        writers = self.record_node.count_publishers(info["topic"] + "/verify") > 0
        record = pairing.take(key, wait=writers)
        at = now()
        with self.lock:
            reg = self.registers[port]
            reg.value, reg.present, reg.record = value, True, record
            reg.arrivals += 1
            releases = self._events(port)
        for task, event in releases:
            self._release(task, event, at)

    def _events(self, port: str) -> list[tuple[str, int]]:
        """The releases an arrival on ``port`` causes: its own events, then its compounds' (timing §3)."""
        inst, name = port.split(".")
        triggers = [name]
        for compound, (mode, members) in self.system.COMPOUNDS.items():
            c_inst, c_name = compound.split(".")
            if c_inst != inst or name not in members:
                continue
            if mode == "or":
                triggers.append(c_name)
                continue
            fresh = self.fresh.setdefault(compound, set())
            fresh.add(name)
            if fresh >= set(members):
                fresh.clear()
                triggers.append(c_name)
        releases = []
        for trigger in triggers:
            for task, cfg in self.tasks.items():
                if cfg.activation == "trigger" and cfg.trigger == trigger and task.startswith(inst + "."):
                    self.counters[task] += 1
                    if self.counters[task] % cfg.prescaler == 0:
                        releases.append((task, self.counters[task]))
        return releases

    def _release(self, task: str, event: int, at: int) -> None:
        if self.started.is_set() and not self.stopping.is_set():  # (none before the agreed start, §4)
            self.dispatcher.release(task, event, at)

    def _sporadic_release(self, task: str) -> None:
        at = now()
        cfg = self.tasks.get(task)
        if cfg is None or cfg.activation != "sporadic":
            self.log.warning(f"{task} is not a sporadic task of this process; not released")
            return
        last = self.last_release.get(task)
        if last is not None and at - last < cfg.min_gap:
            self.log.warning(f"{task} released {at - last} ns after its previous release, sooner than the "
                             f"model's {cfg.min_gap} ns: a broken assumption", throttle_duration_sec=1.0)
        self.last_release[task] = at
        self.counters[task] += 1
        self._release(task, self.counters[task], at)

    # ---------------------------------------------------------------- jobs

    def _run(self, job: Job) -> None:
        inst, name = job.task.split(".")
        spec = self.system.TASKS[job.task]
        with self.lock:
            job.start = now()
            cpu = time.thread_time_ns()  # (a thread waiting for the interpreter lock uses no CPU time)
            read = [(p, self.registers[f"{inst}.{p}"]) for p in spec["reads"]]
            inputs = [Input(r.value, r.present) for _p, r in read]
            sources = {p: r.record for p, r in read}
        self.first_start.setdefault(job.task, job.start)
        stamps = self._hold(job, sources)
        outputs = [Output(message_class(self.system.PORTS[f"{inst}.{p}"]["type"])()
                          if self.system.PORTS[f"{inst}.{p}"]["type"] else None) for p in spec["produces"]]
        try:
            getattr(self.objects[inst], f"on_{name}")(*inputs, *outputs)
        except Exception as err:  # (the user's code: logged, the node goes on)
            self.log.error(f"{job.task} job {job.seq} raised {type(err).__name__}: {err}; it writes nothing",
                           throttle_duration_sec=1.0)
            return
        job.cpu = time.thread_time_ns() - cpu
        job.finish = now()
        writes = {p: self._publish(f"{inst}.{p}", o.value, job, stamps) for p, o in zip(spec["produces"], outputs)}
        self._monitor(job, stamps)
        if self.trace_dir:
            self.records.append({
                "unit": self.name, "task": job.task, "seq": job.seq, "event": job.event, "release": job.release,
                "start": job.start, "finish": job.finish, "cpu": job.cpu, "writes": writes,
                "reads": {p: None if r is None else [r.writer, r.task, r.seq, r.index] for p, r in sources.items()},
                "stamps": [[s.chain, s.position, s.origin, s.first] for s in stamps]})

    def _hold(self, job: Job, sources: dict[str, Record | None]) -> list[Stamp]:
        """The job's stamps, one per role (specs/codegen.md §5)."""
        if not self.monitoring:
            return []
        stamps = []
        for role in self.tasks[job.task].roles:
            if role.position == 0:
                stamps.append(Stamp(role.chain, 0, job.start, self.first_start[job.task]))
                continue
            record = sources.get(role.source)
            held = [s for s in record.stamps if s.chain == role.chain and s.position == role.position - 1] \
                if record is not None else []
            if held:
                stamps.append(Stamp(role.chain, role.position, held[0].origin, held[0].first))
        return stamps

    def _publish(self, port: str, value: Any, job: Job, stamps: list[Stamp]) -> int:
        publisher, records, bound = self.publishers[port]
        try:
            data = serialize_message(to_wire(value, bound))
        except Exception as err:  # (a value of the wrong type)
            self.log.error(f"{job.task} wrote a value to {port} that is not its type: {err}", throttle_duration_sec=1.0)
            return 0
        self.indices[port] += 1
        index = self.indices[port]
        if self.monitoring or self.trace_dir:
            out = port.split(".")[1]
            mine = tuple(s for s in stamps if any(r.chain == s.chain and r.target == out
                                                  for r in self.tasks[job.task].roles))
            record = Record(self.name, index, job.seq, job.task, job.release, job.start, job.finish, job.event,
                            mine, digest(data))
            records.publish(message_class(None)(data=record.encode()))
        publisher.publish(data)
        return index

    def _monitor(self, job: Job, stamps: list[Stamp]) -> None:
        for role in self.tasks[job.task].roles:
            monitor = self.monitors.get(role.chain)
            if monitor is None or role.target:
                continue
            for stamp in stamps:
                if stamp.chain == role.chain:
                    for violation in monitor.on_end(stamp, job.finish):
                        self._violation(violation)

    def _violation(self, v: Violation) -> None:
        text = json.dumps({"chain": v.chain, "metric": v.metric, "value_ns": v.value_ns, "bound_ns": v.bound_ns,
                           "at_ns": v.at_ns})
        self.violations_pub.publish(message_class(None)(data=text))
        self.log.warning(f"chain {v.chain}: {v.metric} {v.value_ns} ns exceeds {v.bound_ns} ns "
                         "(every violation: /verify/violations)", throttle_duration_sec=1.0)

    # ---------------------------------------------------------------- start and stop

    def _connected(self) -> bool:
        """Whether every in-port with a writer in the model is matched with it (values and records), and
        every out-port with as many processes as read it (§4)."""
        for port, (values, records) in self.subscriptions.items():
            if self.system.PORTS[port]["source"] and min(values.get_publisher_count(),
                                                         records.get_publisher_count()) < 1:
                return False
        for port, (values, records, _bound) in self.publishers.items():
            readers = self.system.PORTS[port]["readers"]
            if min(values.get_subscription_count(), records.get_subscription_count()) < readers:
                return False
        return True

    def _wait(self, what: str, done: Any) -> None:
        deadline = time.monotonic() + CONNECT_TIMEOUT_S
        while not done() and not self.stopping.is_set():
            if time.monotonic() > deadline:
                self.log.warning(f"{what}: still waiting after {CONNECT_TIMEOUT_S:.0f} s; starting anyway")
                return
            time.sleep(0.05)

    def _agreed_start(self) -> int:
        """The instant all processes of this run start at: 200 ms after the last one was ready (§4)."""
        if not self.run_id:
            return now()
        ready: dict[str, int] = {}
        string = message_class(None)

        def heard(message: Any) -> None:
            try:
                d = json.loads(message.data)
            except ValueError:
                return
            if isinstance(d, dict) and d.get("run") == self.run_id:
                ready[str(d.get("unit"))] = int(d.get("at", 0))

        self.node.create_subscription(string, "/verify/ready", heard, READY_QOS)
        pub = self.node.create_publisher(string, "/verify/ready", READY_QOS)
        pub.publish(string(data=json.dumps({"run": self.run_id, "unit": self.name, "at": now()})))
        self._wait("the other processes of this run", lambda: set(self.system.UNITS) <= set(ready))
        return max(ready.values(), default=now()) + START_MARGIN_NS

    def spin(self) -> None:
        """Run until asked to stop (SIGINT, SIGTERM) or for ``verify.duration`` s: connect, agree on the
        start, release jobs; then stop releasing, let the running job complete and what it published
        leave, and write the results."""
        executors = []
        for node in (self.node, self.record_node):
            executor = middleware_executor()
            executor.add_node(node)
            thread = threading.Thread(target=self._spin, args=(executor,), daemon=True)
            thread.start()
            executors.append((executor, thread))
        self._wait("the connections of the ports", self._connected)
        start = self._agreed_start()
        while (remaining := start - now()) > 0 and not self.stopping.is_set():
            self.stopping.wait(remaining / 1e9)
        if not self.stopping.is_set():
            self._start_jobs(start)
            self.stopping.wait(self.duration or None)
        self.timers.stop()
        self.dispatcher.stop()
        time.sleep(0.2)  # (what the last jobs published leaves while the middleware is up)
        self._write_results()
        for executor, thread in executors:
            executor.shutdown(timeout_sec=2.0)
            thread.join(timeout=2.0)

    def _spin(self, executor: Any) -> None:
        if self.rt:
            realtime(None, MIDDLEWARE_PRIORITY, self.log, "arrivals")
        with contextlib.suppress(Exception):  # (shutdown)
            executor.spin()

    def _start_jobs(self, start: int) -> None:
        self.started.set()
        self.dispatcher.start(self._scheduling if self.rt else None)
        self.timers.start(start)

    def _timer_scheduling(self) -> None:
        if self.rt:
            realtime(None, TIMER_PRIORITY, self.log, "timers")

    def _scheduling(self) -> None:
        unit = self.config.get("unit", {})
        realtime(unit.get("cpu"), int(unit.get("os_priority", 1)), self.log, self.name)

    def _write_results(self) -> None:
        if self.summary_dir and self.monitors:
            summary = {"node": f"/{self.system.NAMESPACE}/{self.name}",
                       "chains": {c: m.summary() for c, m in self.monitors.items()}}
            with open(os.path.join(self.summary_dir, f"{self.system.NAMESPACE}_{self.name}.json"), "w",
                      encoding="utf-8") as f:
                json.dump(summary, f, indent=1, sort_keys=True)
        if self.trace_dir:
            os.makedirs(self.trace_dir, exist_ok=True)
            with open(os.path.join(self.trace_dir, f"{self.name}.jsonl"), "w", encoding="utf-8") as f:
                for record in self.records:
                    f.write(json.dumps(record) + "\n")


def main(system: ModuleType, argv: list[str] | None = None, stopped: list[int] | None = None) -> int:
    """The process ``argv[1]`` of ``system`` (the generated package's ``system`` module); ``stopped``
    holds the signals that asked it to stop before it could start (it then stops at once)."""
    stopped = stopped if stopped is not None else []
    argv = list(sys.argv if argv is None else argv)
    names = [a for a in argv[1:argv.index("--ros-args") if "--ros-args" in argv else len(argv)]]
    if len(names) != 1 or names[0] not in system.UNITS:
        print(f"usage: {argv[0]} UNIT [--ros-args ...], UNIT one of: {', '.join(system.UNITS)}", file=sys.stderr)
        return 2
    if stopped:
        return 0
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    if "verify.realtime:=false" not in argv:  # (the middleware's threads, made by init, inherit it)
        realtime(None, MIDDLEWARE_PRIORITY, rclpy.logging.get_logger(names[0]), "the middleware")
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    try:
        unit = Unit(system, names[0])
    except ConfigError as err:
        print(f"{names[0]}: {err}", file=sys.stderr)
        rclpy.shutdown()
        return 2
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda _s, _f: unit.stopping.set())
    if stopped:
        unit.stopping.set()
    try:
        unit.spin()
    finally:
        _shut_down(unit)
    return 0


def _shut_down(unit: Unit) -> None:
    """Destroy the nodes and shut rclpy down; if the middleware has not done so in SHUTDOWN_TIMEOUT_S
    (its participant's destruction can hang), leave at once: the results are written."""
    def body() -> None:
        unit.node.destroy_node()
        unit.record_node.destroy_node()
        rclpy.try_shutdown()

    thread = threading.Thread(target=body, name="verify-shutdown", daemon=True)
    thread.start()
    thread.join(SHUTDOWN_TIMEOUT_S)
    if thread.is_alive():
        unit.log.warning(f"the middleware did not shut down in {SHUTDOWN_TIMEOUT_S:.0f} s; leaving without it")
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
