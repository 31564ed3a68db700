"""The live tests' access to ROS 2: the wheels' own environment (``.ros2/``, made by
``scripts/install-tools``; ``VERIFY_ROS2_PYTHON`` names another interpreter), and what the tests do
when it is missing: skip on a developer's machine, fail under CI (``CI=true``)."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
from pathlib import Path

import pytest

from benchmarks.ros2 import missing, python

from .conftest import in_ci

#: how long a run may take beyond its duration (start-up, discovery, the agreed start, shutdown; on a
#: loaded machine importing rclpy in every process alone takes seconds)
GRACE_S = 120


def require_ros2() -> str:
    """The ROS 2 interpreter; skips (fails under CI) unless it imports rclpy and the messages."""
    message = missing()
    if message:
        if in_ci():
            pytest.fail(message)
        pytest.skip(message)
    return python()


def environment(project: Path, home: Path, domain: int) -> dict[str, str]:
    """Loopback-only Fast DDS on a domain of the test's own, the generated package importable."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "RMW_", "PYTHON"))}
    env.update(RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               ROS_DOMAIN_ID=str(domain), ROS_HOME=str(home), ROS_LOG_DIR=str(home / "log"), PYTHONPATH=str(project))
    return env


def start(project: Path, package: str, env: dict[str, str], seconds: float, out: Path,
          *extra: str) -> subprocess.Popen[bytes]:
    """The generated runner: every process of the system for ``seconds``, summaries and job records in
    ``out``/summary and ``out``/trace, its output in ``out``/run.log."""
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "run.log", "wb") as log:  # (the process has its own copy)
        return subprocess.Popen(["timeout", str(int(seconds) + GRACE_S), python(), "-m", f"{package}.run",
                                 "--duration", str(seconds), "--summary-dir", str(out / "summary" / "made"),
                                 "--trace-dir", str(out / "trace"), *extra], cwd=project, env=env, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)


def end(procs: list[subprocess.Popen[bytes]]) -> None:
    """Kill what is left of each started process group (the runner's processes, a probe, a listener)."""
    for proc in procs:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)


#: a probe of the platform: at SCHED_FIFO 99 on one CPU it asks to wake every millisecond and records
#: each wake-up more than 1 ms late ([due, woken] in ns): time the CPU was taken from every thread of the
#: machine (the hypervisor, the kernel, real-time throttling), which no analysis of the model covers
PROBE = """\
import json, os, sys, time
cpu, out, stop = int(sys.argv[1]), sys.argv[2], sys.argv[3]
os.sched_setaffinity(0, {cpu})
try:
    os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(99))
except OSError:
    pass
stalls, due, n = [], time.time_ns(), 0
while True:
    due += 1_000_000
    left = due - time.time_ns()
    if left > 0:
        time.sleep(left / 1e9)
    woken = time.time_ns()
    if woken - due > 1_000_000:
        stalls.append([due, woken])
        due = woken
    n += 1
    if n % 100 == 0 and os.path.exists(stop):
        break
with open(out, "w") as f:
    json.dump(stalls, f)
"""


def probes(directory: Path, stop: Path) -> list[subprocess.Popen[bytes]]:
    """A platform probe (PROBE) per CPU, until ``stop`` exists; their stalls in ``directory``/stalls-CPU.json."""
    script = directory / "probe.py"
    script.write_text(PROBE, encoding="utf-8")
    return [subprocess.Popen(["timeout", "600", python(), str(script), str(cpu), str(directory / f"stalls-{cpu}.json"),
                              str(stop)], start_new_session=True) for cpu in sorted(os.sched_getaffinity(0))]


def stalls(directory: Path) -> list[tuple[int, int]]:
    """The stalls the probes saw, [due, woken] ns."""
    import json

    return sorted((a, b) for path in directory.glob("stalls-*.json") for a, b in json.loads(path.read_text()))


def stall_summary(found: list[tuple[int, int]]) -> str:
    """How many stalls, how long in all, the longest (ms): for a failure's message."""
    lengths = [b - a for a, b in found]
    if not lengths:
        return "no stall"
    return f"{len(lengths)} stalls, {sum(lengths) / 1e6:.1f} ms in all, the longest {max(lengths) / 1e6:.1f} ms"


def overlaps(window: tuple[int, int], found: list[tuple[int, int]]) -> bool:
    return any(a < window[1] and window[0] < b for a, b in found)
