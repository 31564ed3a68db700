"""Building and running generated ROS 1 projects: the tools, a private master, a recorder.

Used by the live tests (tests/test_gen_ros1_live.py) and the monitor-cost benchmark (benchmarks/ros1.py).
Everything runs under a timeout on loopback, with ROS's home and logs in a directory of the caller's.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SYSTEM_PYTHON = "/usr/bin/python3"  # Debian's, which has rospy
RECORDER = ROOT / "tests" / "ros" / "record.py"


def missing_tools() -> list[str]:
    """What building and running needs and this machine lacks (scripts/install-tools installs it)."""
    missing = [tool for tool in ("cmake", "g++", "roscore", "roslaunch", "rosbag") if shutil.which(tool) is None]
    missing += [package for header, package in (("ros/ros.h", "libroscpp-dev"),
                                                ("sensor_msgs/LaserScan.h", "libsensor-msgs-dev"),
                                                ("geometry_msgs/Twist.h", "libgeometry-msgs-dev"),
                                                ("nav_msgs/Path.h", "libnav-msgs-dev"))
                if not os.path.exists(f"/usr/include/{header}")]
    for module, package in (("rospy", "python3-rospy"), ("rosbag", "python3-rosbag"),
                            ("sensor_msgs.msg", "python3-sensor-msgs"), ("nav_msgs.msg", "python3-nav-msgs")):
        if not os.path.exists(SYSTEM_PYTHON) or subprocess.run([SYSTEM_PYTHON, "-c", f"import {module}"],
                                                               capture_output=True).returncode != 0:
            missing.append(package)
    return missing


def build(project: Path) -> str:
    """Configure and build the generated project with CMake; returns the compiler's output. The build
    type is the generated default's (RelWithDebInfo: -O2 -DNDEBUG) without the debug information, which
    takes a quarter of the compile time and changes no code."""
    build_dir = project / "build"
    configure = subprocess.run(["cmake", "-S", str(project), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                                "-DCMAKE_CXX_FLAGS_RELEASE=-O2 -DNDEBUG"], capture_output=True, text=True, timeout=300)
    if configure.returncode != 0:
        raise RuntimeError(configure.stdout + configure.stderr)
    made = subprocess.run(["cmake", "--build", str(build_dir), "-j2"], capture_output=True, text=True, timeout=900)
    if made.returncode != 0:
        raise RuntimeError(made.stdout + made.stderr)
    return made.stdout + made.stderr


def burn_execution_times(project: Path, wcet_ns: dict[str, int]) -> None:
    """Fill every ``on_TASK`` of the user skeletons with a job that burns its execution time of its thread's
    CPU time (``burn_cpu``: the thread's CPU clock, the quantity a WCET and the job records' ``cpu`` are;
    not wall time, which would count what other threads took)."""
    for path in (project / "user").glob("*.hpp"):
        text = path.read_text(encoding="utf-8")

        def body(m: re.Match[str]) -> str:
            burn = f"verify_ros1::burn_cpu({wcet_ns[m.group(1)]});"
            return f"void on_{m.group(1)}({m.group(2)}) override {{\n    {burn}\n  }}"

        path.write_text(re.sub(r"void on_(\w+)\((.*?)\) override \{\n  \}", body, text, flags=re.S), encoding="utf-8")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def ros_environment(project: Path, home: Path, port: int) -> dict[str, str]:
    env = dict(os.environ)
    env.update(ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOSTNAME="127.0.0.1", ROS_HOME=str(home),
               ROS_LOG_DIR=str(home / "log"), ROS_PACKAGE_PATH=f"{project}:/usr/share", PYTHONPATH="")
    return env


@contextlib.contextmanager
def master(project: Path, home: Path) -> Iterator[dict[str, str]]:
    """A roscore on a free loopback port (under a timeout); yields the environment that reaches it."""
    port = _free_port()
    env = ros_environment(project, home, port)
    core = subprocess.Popen(["timeout", "300", "roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    break
            time.sleep(0.1)
        else:
            raise AssertionError("roscore did not come up")
        time.sleep(1.0)  # (rosout registers)
        yield env
    finally:
        _stop(core)


def _stop(process: subprocess.Popen[str] | subprocess.Popen[bytes]) -> None:
    """SIGINT to the process's group, SIGKILL after 15 s."""
    if process.poll() is not None:
        return
    os.killpg(process.pid, signal.SIGINT)
    try:
        process.wait(timeout=15)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def run_system(env: dict[str, str], package: str, launch: str, seconds: float, record_to: Path,
               topics: list[str], summary_dir: Path, beside: list[list[str]] | None = None,
               launch_args: list[str] | None = None) -> str:
    """Record, launch the system with tracing for ``seconds``, stop it (SIGINT, as roslaunch is
    stopped), stop the recorder; returns roslaunch's output. ``beside``: commands that run meanwhile
    (drivers of sporadic tasks). The nodes make ``summary_dir`` (and its parents) when it is missing."""
    drivers = [subprocess.Popen(["timeout", str(int(seconds) + 120), *command], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True) for command in beside or []]
    recorder = subprocess.Popen(["timeout", str(int(seconds) + 120), SYSTEM_PYTHON, str(RECORDER), str(record_to),
                                 *topics], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
    system = None
    try:
        deadline = time.monotonic() + 30
        while not (record_to.exists() and "ready" in record_to.read_text(encoding="utf-8")):
            assert time.monotonic() < deadline and recorder.poll() is None, "the recorder did not start"
            time.sleep(0.1)
        time.sleep(0.5)
        command = ["timeout", "-s", "INT", "-k", "30", str(seconds), "roslaunch", package, launch, "trace:=true",
                   f"summary_dir:={summary_dir}", *(launch_args or [])]
        system = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  start_new_session=True)
        output, _ = system.communicate(timeout=seconds + 60)
        time.sleep(1.0)  # (the last messages reach the recorder)
    finally:
        for process in (system, recorder, *drivers):
            if process is not None:
                _stop(process)
    return output


# ------------------------------------------------------------------ what was recorded


def recorded(path: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


def jobs(records: list[dict[str, object]]) -> list[dict[str, object]]:
    return [json.loads(str(r["data"])) for r in records if r["topic"] == "/verify/jobs"]


def decode_record(hex_bytes: str) -> dict[str, object]:
    """A record as recorded on TOPIC/verify: an std_msgs/UInt8MultiArray (an empty layout) holding the
    out-of-band record of a message (specs/codegen.md §6)."""
    raw = bytes.fromhex(hex_bytes)
    (dims,) = struct.unpack_from("<I", raw, 0)
    assert dims == 0
    (_offset, length) = struct.unpack_from("<II", raw, 4)
    data = raw[12:12 + length]
    assert len(data) == length and data[:4] == b"VFY2"
    index, seq, release, start, finish, event, n = struct.unpack_from("<QQqqqQH", data, 4)
    at = 4 + 50
    stamps = []
    for _ in range(n):
        stamps.append(struct.unpack_from("<HHqq", data, at))
        at += 20
    assert at == len(data)
    return {"index": index, "seq": seq, "release": release, "start": start, "finish": finish, "event": event,
            "stamps": stamps}
