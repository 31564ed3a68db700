"""ROS 2 stage: what the generated rclpy nodes' glue costs, and how tight the executor analysis is
against them (issue 35, item 6).

``ros2-glue`` runs a generated pipeline live (a 100 Hz source and a relay on a single-threaded
executor of the model on cpu0, a relay and a sink as tasks of their own on cpu1; one chain through
all; empty functional code) with the generated runner in the ROS 2 wheels' environment (``.ros2/``,
scripts/install-tools), and from the job records reports:
- the glue's cost per job: start to completion of a job whose functional code is empty (reading the
  registers, making the output messages, calling it), median / p99 / max;
- per hop: a writer job's completion to the release of the reader job its message triggered
  (serializing, the record, publishing, Fast DDS on loopback, the arrival, pairing), median / p99 / max;
- the **arrival cost**: the CPU time the sink's process (one task, cpu1, empty functional code) spends
  per value it takes beyond its jobs' own time: its process's CPU time (``/proc/PID/stat``, sampled
  every 100 ms) over the run's steady part (from 2 s after its first job to its last sample) less the
  start-to-completion time of its jobs released then, divided by the values it took then (one per
  job: a value and its record) — what rclpy's executor spends taking a message, the number
  ``arrival_cost`` declares (specs/timing.md §6.6), measured on longer runs (not in ``--quick``);
- per task, the largest measured response time against the bound ``analyze`` gives (the model gives
  every task 2 ms, which covers the glue), for the executor's callbacks and the plain tasks.
The package is generated once (untimed) in ``benchmarks/out/ros2-pipeline``.
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
ROOT = Path(__file__).resolve().parent.parent

PIPELINE = """
component Source {
  out o : Msg
  task Emit {
    produces o
    wcet 2 ms
  }
}
component Relay {
  in i : Msg
  out o : Msg
  task Pass {
    reads i
    produces o
    wcet 2 ms
  }
}
component Sink {
  in i : Msg
  task Take {
    reads i
    wcet 2 ms
  }
}
message Msg = ros "std_msgs/String"
system Pipeline {
  core cpu0
  core cpu1
  executor ex single_threaded on cpu0 priority 4
  instance src : Source {
    task Emit executor ex timer 100 Hz
  }
  instance r1 : Relay on cpu1 {
    task Pass priority 3 trigger i
  }
  instance r2 : Relay {
    task Pass executor ex trigger i
  }
  instance sink : Sink on cpu1 {
    task Take priority 1 trigger i
  }
  connect src.o -> r1.i delay 50 us .. 5 ms
  connect r1.o -> r2.i delay 50 us .. 5 ms
  connect r2.o -> sink.i delay 50 us .. 5 ms
  chain through: src.o -> r1.o -> r2.o -> sink.Take {
    reaction_time <= 100 ms
  }
}
"""


def python() -> str:
    """The interpreter of the ROS 2 wheels' environment (``.ros2/``; ``VERIFY_ROS2_PYTHON`` names another)."""
    return os.environ.get("VERIFY_ROS2_PYTHON") or str(ROOT / ".ros2" / "bin" / "python")


#: what the ROS 2 stages and live tests import: rclpy and the message packages they use
PROBE = "import rclpy, std_msgs.msg, sensor_msgs.msg, geometry_msgs.msg, nav_msgs.msg"


def missing() -> str | None:
    """Why the ROS 2 wheels cannot be used here, or None when ``python()`` imports all of ``PROBE``."""
    try:
        ok = subprocess.run([python(), "-c", PROBE], capture_output=True, timeout=60).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        ok = False
    return None if ok else f"ROS 2 wheels missing: {python()} cannot import rclpy and the messages " \
                           "(scripts/install-tools installs them into .ros2/)"


def pipeline_text(n_tasks: int, seed: int, **_: object) -> str:
    return PIPELINE


def _spread(values: list[int]) -> str:
    ordered = sorted(values)
    p99 = ordered[max((99 * len(ordered) + 99) // 100, 1) - 1]
    return f"{statistics.median(ordered) / 1000:.0f} / {p99 / 1000:.0f} / {ordered[-1] / 1000:.0f} us"


def hops(jobs: list[dict]) -> list[int]:
    """Writer completion to reader release, per job released by the message it read (ns)."""
    finish = {(j["task"], j["seq"]): j["finish"] for j in jobs}
    out = []
    for j in jobs:
        read = j["reads"].get("i")
        if read is not None and read[3] == j["event"] and (read[1], read[2]) in finish:
            out.append(j["release"] - finish[(read[1], read[2])])
    return out


#: the process whose CPU time is sampled (the sink: one task, one in-port)
SINK_UNIT = "sink_Take"
#: the start of the steady part, after the sink's first job (Python's first pass through the glue)
STEADY_NS = 2_000_000_000


def _unit_pids(project: Path, unit: str) -> list[int]:
    """The processes running ``unit`` of the package in ``project`` (their command line names both)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                words = (entry / "cmdline").read_bytes().split(b"\0")
            except OSError:
                continue
            if unit.encode() in words and any(b"pipeline_nodes" in w for w in words):
                found.append(int(entry.name))
    return found


def _cpu_ns(pid: int) -> int | None:
    """User plus system CPU time of ``pid`` (ns), None once it is gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[11]) + int(fields[12])) * 1_000_000_000 // os.sysconf("SC_CLK_TCK")


def arrival_cost(samples: list[tuple[int, int]], jobs: list[dict]) -> int | None:
    """The sink's CPU per value taken beyond its jobs' time (ns), from ``samples`` (CLOCK_REALTIME ns, CPU
    ns) over the steady part; None when the run is too short for one."""
    mine = sorted((j for j in jobs if j["unit"] == SINK_UNIT), key=lambda j: j["release"])
    if not mine or len(samples) < 2:
        return None
    begin = mine[0]["release"] + STEADY_NS
    steady = [s for s in samples if s[0] >= begin]
    if len(steady) < 2:
        return None
    (t0, c0), (t1, c1) = steady[0], steady[-1]
    inside = [j for j in mine if t0 <= j["release"] and j["finish"] <= t1]
    if not inside:
        return None
    return (c1 - c0 - sum(j["finish"] - j["start"] for j in inside)) // len(inside)


def register(stage: Callable[..., Callable], error: type[Exception], unavailable: dict[str, str]) -> None:
    reason = missing()
    if reason:
        unavailable["ros2-glue"] = reason
        return
    project = OUT / "ros2-pipeline"

    def setup() -> None:
        from verify.cli import main

        OUT.mkdir(parents=True, exist_ok=True)
        model_file = OUT / "ros2-pipeline.vfy"
        model_file.write_text(PIPELINE, encoding="utf-8")
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            if main(["gen", "ros2", str(model_file), "-o", str(project), "--force"]) != 0:
                raise error("verify gen ros2 failed on the pipeline", {})

    def live(seconds: float) -> tuple[list[dict], list[tuple[int, int]]]:
        """The job records of a run, and the sink process's CPU time sampled during it."""
        with tempfile.TemporaryDirectory() as tmp:
            env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "RMW_", "PYTHON"))}
            env.update(RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                       ROS_DOMAIN_ID=str(90 + os.getpid() % 10), ROS_HOME=tmp, PYTHONPATH=str(project))
            run = subprocess.Popen(["timeout", str(int(seconds) + 120), python(), "-m", "pipeline_nodes.run",
                                    "--duration", str(seconds), "--trace-dir", tmp], env=env, cwd=project,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            samples: list[tuple[int, int]] = []
            while run.poll() is None:
                pids = _unit_pids(project, SINK_UNIT)
                cpu = _cpu_ns(pids[0]) if len(pids) == 1 else None
                if cpu is not None:
                    samples.append((time.time_ns(), cpu))
                time.sleep(0.1)
            if run.returncode != 0:
                raise subprocess.CalledProcessError(run.returncode, "pipeline_nodes.run")
            jobs = [json.loads(line) for f in sorted(Path(tmp).glob("*.jsonl")) for line in f.read_text().splitlines()]
            return jobs, samples

    @stage("ros2-glue", "the generated ROS 2 (rclpy) nodes: the glue's cost per job and per hop (median / p99 / "
           "max), the CPU time a process spends per value it takes (arrival cost), and per task the largest "
           "measured response time over the bound analyze gives (the size is "
           "ignored)", sizes=(1,), quick_sizes=(1,), generator=pipeline_text, setup=setup,
           params={"seconds": 10.0}, quick_params={"seconds": 1.0})
    def ros2_glue(inst, seconds: float) -> dict:
        from verify import load_text
        from verify.timing import analyze

        try:
            jobs, samples = live(seconds)
        except (OSError, subprocess.SubprocessError) as err:
            raise error(f"{type(err).__name__}: {str(err)[:200]}", {}) from None
        if not jobs:
            raise error("no job was recorded", {})
        analysis = analyze(load_text(PIPELINE).system())
        row = {"glue per job": _spread([j["finish"] - j["start"] for j in jobs]), "per hop": _spread(hops(jobs))}
        cost = arrival_cost(samples, jobs)
        row["arrival cost"] = f"{cost / 1000:.0f} us" if cost is not None else "-"
        for timing in analysis.tasks:
            times = [j["finish"] - j["release"] for j in jobs if j["task"] == timing.id]
            if times:
                row[f"{timing.id} measured/bound"] = f"{max(times) / 1e9 / float(timing.response.wcrt):.2f}"
        row["jobs"] = str(len(jobs))
        return row
