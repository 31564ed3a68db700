"""Real LTTng traces made here, for tests/test_trace_lttng.py and the `trace-read` benchmark stage:
``tests/trace/ros2_events.c`` (the `ros2` provider's events with ros2_tracing's names and fields,
through Debian's liblttng-ust) compiled with the system compiler, and recorded by Debian's LTTng
(`lttng-sessiond --daemonize`, one session per recording)."""
from __future__ import annotations

import os
import shutil
import subprocess
import uuid
from pathlib import Path

SOURCES = Path(__file__).resolve().parent.parent / "tests" / "trace"
HEADER = "/usr/include/x86_64-linux-gnu/lttng/tracepoint.h"


def missing_tools() -> list[str]:
    """What recording needs and this machine lacks (scripts/install-tools installs it)."""
    missing = [tool for tool in ("cc", "lttng", "lttng-sessiond") if shutil.which(tool) is None]
    if not any(os.path.exists(p) for p in (HEADER, "/usr/include/lttng/tracepoint.h")):
        missing.append("liblttng-ust-dev")
    return missing


def build(directory: Path) -> Path:
    """``ros2_events`` compiled in ``directory``."""
    for name in ("ros2_events.c", "ros2_tp.h"):
        shutil.copy(SOURCES / name, directory / name)
    program = directory / "ros2_events"
    subprocess.run(["cc", "-O2", "-Wall", "-Wextra", "-Werror", "-I.", "-o", str(program), "ros2_events.c",
                    "-llttng-ust", "-ldl"], cwd=directory, check=True, capture_output=True, text=True)
    return program


def session_daemon() -> None:
    """A session daemon for this user (started, daemonized, when none answers)."""
    if subprocess.run(["lttng", "list"], capture_output=True).returncode == 0:
        return
    started = subprocess.run(["lttng-sessiond", "--daemonize"], capture_output=True, text=True, timeout=60)
    # (another test process may have started one meanwhile: what matters is that one answers now)
    if subprocess.run(["lttng", "list"], capture_output=True).returncode != 0:
        raise RuntimeError(f"lttng-sessiond --daemonize: {started.stderr.strip() or started.returncode}")


def _lttng(*args: str) -> None:
    subprocess.run(["lttng", *args], check=True, capture_output=True, text=True, timeout=60)


def realtime_prefix() -> list[str]:
    """``chrt -f 99`` when this user may run a program at a real-time priority (root), else nothing: a
    program burning known times is then not preempted by the machine's other work, the generated ROS 2
    nodes' real-time threads (priorities 97 to 99, specs/codegen.md) of a test running beside it included
    (SCHED_FIFO does not preempt at equal priority)."""
    if shutil.which("chrt") and subprocess.run(["chrt", "-f", "99", "true"], capture_output=True).returncode == 0:
        return ["chrt", "-f", "99"]
    return []


def record(program: Path, args: list[str], output: Path, *, blocking: bool = False, realtime: bool = False) -> Path:
    """Run ``program args`` in a session of its own that records the `ros2` provider's events, with the
    vpid and vtid contexts, into ``output``; ``blocking``: the application waits rather than lose an
    event when the buffers are full (for long recordings); ``realtime``: at a real-time priority when
    this user may (``realtime_prefix``)."""
    session_daemon()
    name = "verify-" + uuid.uuid4().hex[:12]
    _lttng("create", name, f"--output={output}")
    try:
        env = dict(os.environ)
        if blocking:
            _lttng("enable-channel", "-u", "-s", name, "--subbuf-size=8M", "--num-subbuf=8",
                   "--blocking-timeout=inf", "ch")
            _lttng("enable-event", "-u", "-s", name, "-c", "ch", "ros2:*")
            _lttng("add-context", "-u", "-s", name, "-c", "ch", "-t", "vpid", "-t", "vtid")
            env["LTTNG_UST_ALLOW_BLOCKING"] = "1"
        else:
            _lttng("enable-event", "-u", "-s", name, "ros2:*")
            _lttng("add-context", "-u", "-s", name, "-t", "vpid", "-t", "vtid")
        _lttng("start", name)
        # (the application registers with the session daemon before its first event: wait for it)
        env["LTTNG_UST_REGISTER_TIMEOUT"] = "-1"
        prefix = realtime_prefix() if realtime else []
        subprocess.run([*prefix, str(program), *args], check=True, env=env, timeout=600)
        _lttng("stop", name)
    finally:
        subprocess.run(["lttng", "destroy", name], capture_output=True, timeout=60)
    return output
