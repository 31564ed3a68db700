"""`verify trace` on bags (specs/trace.md §1.3): a ROS 2 bag in MCAP storage and a ROS 1 bag, written
with `rosbags` (the `trace` extra) with known timestamps: the talker's topic every second is its timer's
period; every half second, E802."""
from __future__ import annotations

from pathlib import Path

import pytest

from verify.cli import main

from .conftest import in_ci
from .test_trace import COMPLETED


def _rosbags():
    try:
        import rosbags.rosbag2  # noqa: F401
    except ImportError:
        if in_ci():
            raise
        pytest.skip("rosbags is not installed (the `trace` extra)")


def _ros2_bag(path: Path, period_ns: int, count: int = 10) -> Path:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    string = store.types["std_msgs/msg/String"]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as bag:
        chatter = bag.add_connection("/chatter", string.__msgtype__, typestore=store)
        rosout = bag.add_connection("/rosout_agg", string.__msgtype__, typestore=store)
        for k in range(count):
            data = store.serialize_cdr(string(data=f"hello {k}"), string.__msgtype__)
            bag.write(chatter, 10**9 + k * period_ns, data)
            bag.write(rosout, 10**9 + k * period_ns + 1000, data)
    return path


def _ros1_bag(path: Path, period_ns: int, count: int = 10) -> Path:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    string = store.types["std_msgs/msg/String"]
    with Writer(path) as bag:
        chatter = bag.add_connection("/chatter", string.__msgtype__, typestore=store)
        for k in range(count):
            data = store.serialize_ros1(string(data=f"hello {k}"), string.__msgtype__)
            bag.write(chatter, 10**9 + k * period_ns, data)
    return path


def test_a_ros2_mcap_bag_gives_the_talkers_period(tmp_path, capsys):
    _rosbags()
    bag = _ros2_bag(tmp_path / "bag", 10**9)
    assert (bag / "bag.mcap").exists()
    assert main(["trace", str(COMPLETED), str(bag)]) == 0
    out, err = capsys.readouterr()
    assert "talker.timer_callback_0: 10 messages on topic `/chatter`" in out and "mean period 1 s" in out
    assert "E802" not in err and "E801" not in err
    assert "topic `/rosout_agg` is not paired with a task: no out-port of the model is this topic" in err


def test_a_ros2_bag_at_twice_the_rate_is_a_period_off_the_model(tmp_path, capsys):
    _rosbags()
    bag = _ros2_bag(tmp_path / "bag", 5 * 10**8)
    assert main(["trace", str(COMPLETED), str(bag)]) == 1
    err = capsys.readouterr().err
    assert err.count("error[") == 1 and "error[E802]" in err and "mean period of 500 ms" in err
    assert "completed.vfy:31:41" in err  # the timer's `1 s`


def test_a_ros1_bag_gives_the_talkers_period(tmp_path, capsys):
    _rosbags()
    bag = _ros1_bag(tmp_path / "run.bag", 10**9)
    assert main(["trace", str(COMPLETED), str(bag)]) == 0
    assert "mean period 1 s" in capsys.readouterr().out


def test_a_broken_bag_is_e806(tmp_path, capsys):
    _rosbags()
    bag = tmp_path / "broken.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    assert main(["trace", str(COMPLETED), str(bag)]) == 2
    err = capsys.readouterr().err
    assert "error[E806]" in err and "cannot be read as a bag" in err and "Traceback" not in err
