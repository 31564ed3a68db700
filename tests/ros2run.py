"""The live tests' access to ROS 2: the wheels' own environment (``.ros2/``, made by
``scripts/install-tools``; ``VERIFY_ROS2_PYTHON`` names another interpreter), and what the tests do
when it is missing: skip on a developer's machine, fail under CI (``CI=true``)."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from .conftest import ROOT, in_ci

#: how long a run may take beyond its duration (start-up, discovery, the agreed start, shutdown; on a
#: loaded machine importing rclpy in every process alone takes seconds)
GRACE_S = 120


def python() -> str:
    return os.environ.get("VERIFY_ROS2_PYTHON") or str(ROOT / ".ros2" / "bin" / "python")


def require_ros2() -> str:
    """The ROS 2 interpreter; skips (fails under CI) unless it imports rclpy and the messages."""
    probe = "import rclpy, std_msgs.msg, sensor_msgs.msg, geometry_msgs.msg, nav_msgs.msg"
    try:
        ok = subprocess.run([python(), "-c", probe], capture_output=True, timeout=60).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        ok = False
    if not ok:
        message = f"ROS 2 wheels missing: {python()} cannot import rclpy (scripts/install-tools installs them)"
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
    log = open(out / "run.log", "wb")  # (closed with the process: the test waits for it)
    return subprocess.Popen(["timeout", str(int(seconds) + GRACE_S), python(), "-m", f"{package}.run",
                             "--duration", str(seconds), "--summary-dir", str(out / "summary" / "made"),
                             "--trace-dir", str(out / "trace"), *extra], cwd=project, env=env, stdout=log,
                            stderr=subprocess.STDOUT)
