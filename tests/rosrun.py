"""The live tests' access to ROS 1 (benchmarks/roslive.py), and what they do when it is missing: skip on
a developer's machine, fail under CI (``CI=true``): the project's set-up
(``scripts/install-tools``) installs it.
"""
from __future__ import annotations

import pytest

from benchmarks.roslive import (RECORDER, SYSTEM_PYTHON, build, burn_execution_times, decode_record, jobs, master,
                               recorded, run_system)

from .conftest import in_ci

__all__ = ["RECORDER", "SYSTEM_PYTHON", "build", "burn_execution_times", "decode_record", "jobs", "master", "recorded",
           "require_ros", "run_system"]


def require_ros() -> None:
    """Skip (fail under CI) unless CMake, a C++ compiler, roscore, roslaunch and rospy are here."""
    from benchmarks.roslive import missing_tools

    missing = missing_tools()
    if missing:
        message = f"ROS 1 tools missing: {', '.join(missing)} (scripts/install-tools installs them)"
        if in_ci():
            pytest.fail(message)
        pytest.skip(message)
