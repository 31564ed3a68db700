"""`verify gen ros1` without ROS: what it writes, what it leaves alone, what it refuses.

(tests/test_gen_ros1_live.py builds and runs the generated nodes.)
"""
from __future__ import annotations

import shutil
from fractions import Fraction
from pathlib import Path

import pytest

import verify
from verify.cli import main
from verify.gen import ros1
from verify.gen.tree import intact

from .builders import project_files
from .conftest import EXAMPLES

NAVIGATION = EXAMPLES / "navigation"


def test_generates_the_project_layout(navigation_models, tmp_path, capsys):
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project)]) == 0
    files = project_files(project)
    for path in ("CMakeLists.txt", "package.xml", "config/parameters.yaml", "launch/Navigation.launch",
                 "include/verify_ros1/runtime.hpp", "include/verify_ros1/monitor.hpp",
                 "include/verify_ros1/envelope.hpp", "glue/ObstacleAvoidance.hpp", "glue/ObstacleAvoidance_main.cpp",
                 "user/ObstacleAvoidance.hpp", "user/types/LaserScan.hpp", "user/user.cmake"):
        assert path in files, path
    out = capsys.readouterr().out
    assert out.startswith("generated ros1 code for system Navigation in ")
    assert "written: 28" in out


def test_output_is_deterministic(navigation_models):
    model = verify.load(str(navigation_models / "navigation.vfy")).system(None)
    assert ros1.generate(model) == ros1.generate(model)


def test_every_glue_file_is_stamped_and_no_user_file_is(navigation_models):
    model = verify.load(str(navigation_models / "navigation.vfy")).system(None)
    for f in ros1.generate(model).files:
        assert intact(f.text) == (f.owner == "glue"), f.path


def test_a_hand_edited_skeleton_survives_regeneration_byte_for_byte(navigation_models, tmp_path, capsys):
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project)]) == 0
    skeleton = project / "user" / "Mapper.hpp"
    mine = skeleton.read_bytes().replace(b"override {\n  }", b"override {\n    map = scan.value();  // mine\n  }")
    skeleton.write_bytes(mine)
    before = project_files(project)
    capsys.readouterr()
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project)]) == 0
    assert project_files(project) == before
    out = capsys.readouterr().out
    assert "unchanged: 17" in out and "left alone (yours): 11" in out and "    user/Mapper.hpp" in out
    assert "written" not in out


def test_a_system_with_holes_is_refused_with_a_pointer_to_synth(navigation_models, tmp_path, capsys):
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(navigation_models / "navigation-holes.vfy"), "-o", str(project)]) == 2
    err = capsys.readouterr().err
    assert "error[E218]: `gen` needs a configured system, but `oa.OATask` has a synthesis hole" in err
    assert "navigation-holes.vfy:17:" in err and "run `synth`" in err
    assert not project.exists()


def test_an_edited_glue_file_is_never_replaced_and_nothing_is_written(navigation_models, tmp_path, capsys):
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project)]) == 0
    glue = project / "glue" / "Laser.hpp"
    edited = glue.read_text(encoding="utf-8") + "// my fix\n"
    glue.write_text(edited, encoding="utf-8")
    (project / "config" / "parameters.yaml").unlink()
    capsys.readouterr()
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project)]) == 2
    err = capsys.readouterr().err
    assert "error[E601]:" in err and "glue/Laser.hpp was edited by hand; it is not replaced" in err
    assert "--force" in err
    assert glue.read_text(encoding="utf-8") == edited
    assert not (project / "config" / "parameters.yaml").exists()  # nothing written
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project), "--force"]) == 0
    assert intact(glue.read_text(encoding="utf-8"))


def test_a_file_in_the_way_that_gen_did_not_write_is_refused(navigation_models, tmp_path, capsys):
    project = tmp_path / "out"
    project.mkdir()
    (project / "CMakeLists.txt").write_text("project(mine)\n", encoding="utf-8")
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project), "--format", "json"]) == 2
    out = capsys.readouterr().out
    assert '"code": "E601"' in out and "was not written by verify gen" in out
    assert (project / "CMakeLists.txt").read_text(encoding="utf-8") == "project(mine)\n"


def test_an_output_that_is_a_file_is_refused(navigation_models, tmp_path, capsys):
    target = tmp_path / "out"
    target.write_text("x", encoding="utf-8")
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(target)]) == 2
    assert "E004" in capsys.readouterr().err


def test_an_unknown_target_is_a_usage_error(navigation_models, capsys):
    assert main(["gen", "ros3", str(navigation_models / "navigation.vfy"), "-o", "x"]) == 2
    assert "invalid choice: 'ros3'" in capsys.readouterr().err


def test_parameters_are_exact_and_complete(tmp_path, write):
    path = write({"main.vfy": _TRICKY})
    model = verify.load(path).system(None)
    yaml = next(f.text for f in ros1.generate(model).files if f.path == "config/parameters.yaml")
    assert 'period_ns: "100000000/3"  # 1/30 s' in yaml  # 30 Hz, exactly
    assert 'trigger: "both"' in yaml and "prescaler: 2" in yaml
    assert 'min_ns: "50000000"' in yaml and 'max_ns: "200000000"' in yaml
    assert 'nodes: ["n_src", "sink"]' in yaml


def test_os_priorities_keep_the_models_order():
    tasks = [7, 3, 3, 100, 0]
    model = type("M", (), {"tasks": [type("T", (), {"priority": p})() for p in tasks]})()
    got = ros1.os_priorities(model)  # type: ignore[arg-type]
    levels = sorted(set(tasks))
    values = [got[p] for p in levels]
    assert values == sorted(set(values)) and values[0] == ros1.OS_PRIORITY_LOW and values[-1] == ros1.OS_PRIORITY_HIGH


def test_names_cpp_or_ros_reserve_are_mangled():
    assert ros1.cpp("class") == "class_" and ros1.cpp("_x") == "_x_" and ros1.cpp("a__b") == "a__b_"
    assert ros1.cpp("scan") == "scan"
    assert ros1.ros_name("_src") == "n_src"
    assert ros1.package_name("NavigationHoles") == "navigation_holes_nodes"
    assert ros1.nanoseconds(Fraction(1, 30)) == "100000000/3"


#: names C++ and ROS reserve, a message type named like a component, a rational period, compounds, a
#: sporadic task: the generated code must compile (tests/test_gen_ros1_live.py builds it)
_TRICKY = """
component Src {
  out class : Sink
  task new {
    produces class
    wcet 1 ms
  }
}
component Sink {
  in x : Sink
  in y : Sink
  in both = x & y
  in any = x | y
  task Both cooperative {
    reads x
    reads y
    wcet 1 ms
  }
  task Any cooperative {
    reads x optional
    reads y
    wcet 1 ms
  }
  task Kick {
    wcet 100 us
  }
}
system Tricky {
  core cpu0
  instance _src : Src on cpu0 {
    task new priority 2 timer 30 Hz
  }
  instance sink : Sink on cpu0 {
    task Both priority 1 trigger both every 2
    task Any priority 1 trigger any
    task Kick priority 3 sporadic 50 ms .. 200 ms
  }
  connect _src.class -> sink.x
  connect _src.class -> sink.y
}
"""


def test_the_monitor_library_works_from_hand_written_code(tmp_path):
    """tests/ros/monitor_check.cpp uses only monitor.hpp and envelope.hpp (no ROS, no generated code):
    known answers of the chain monitor and the out-of-band record's round trip, built with -Wall -Wextra -Werror."""
    import shutil
    import subprocess

    from .conftest import ROOT, in_ci

    compiler = shutil.which("g++")
    if compiler is None:
        if in_ci():
            pytest.fail("g++ missing (scripts/install-tools installs it)")
        pytest.skip("g++ missing")
    binary = tmp_path / "monitor_check"
    include = ROOT / "verify" / "gen" / "ros1_runtime"
    built = subprocess.run([compiler, "-std=c++17", "-Wall", "-Wextra", "-Werror", f"-I{include}",
                            str(ROOT / "tests" / "ros" / "monitor_check.cpp"), "-o", str(binary)],
                           capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    ran = subprocess.run([str(binary), str(scratch)], capture_output=True, text=True, timeout=60)
    assert ran.returncode == 0, ran.stdout
    assert (scratch / "latency" / "run1" / "n.json").is_file()  # (summary_dir:=… made when it was missing)


def test_a_fifo_or_junk_in_the_way_is_refused_without_blocking(navigation_models, tmp_path, capsys):
    import os

    project = tmp_path / "out"
    (project / "config").mkdir(parents=True)
    os.mkfifo(project / "config" / "parameters.yaml")
    (project / "user").mkdir()
    os.mkfifo(project / "user" / "Base.hpp")
    (project / "CMakeLists.txt").write_bytes(b"\x1b[31mred\x00\xff\n")
    assert main(["gen", "ros1", str(navigation_models / "navigation.vfy"), "-o", str(project)]) == 2
    err = capsys.readouterr().err
    assert "config/parameters.yaml was not written by verify gen" in err
    assert "user/Base.hpp is not a regular file" in err
    assert "\x1b" not in err and "\\x1b[31mred" in err


def test_a_system_with_ros2_executors_is_refused_and_nothing_is_written(tmp_path, capsys):
    """The ros1 target gives every task a thread of its own; executor callbacks share one (specs/timing.md
    §9): E602 at every executor, exit 2, no file written."""
    out = tmp_path / "out"
    path = EXAMPLES / "autoware-reference" / "autoware-executors.vfy"
    assert main(["gen", "ros1", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("error[E602]: executor `") == 4 and "autoware-executors.vfy:16:3" in err
    assert not out.exists()


# ------------------------------------------------------------------ message types bound to ROS messages


def _generated(path: Path) -> dict[str, str]:
    return {f.path: f.text for f in ros1.generate(verify.load(str(path)).system(None)).files}


def test_a_bound_type_is_its_ros_message_in_the_user_header_the_glue_and_the_build():
    files = _generated(NAVIGATION / "navigation-ros.vfy")
    scan = files["user/types/LaserScan.hpp"]
    assert "#include <sensor_msgs/LaserScan.h>" in scan and "using LaserScan = ::sensor_msgs::LaserScan;" in scan
    glue = files["glue/ObstacleAvoidance.hpp"]
    assert "verify_ros1::InPort<msg::LaserScan, ::sensor_msgs::LaserScan> port_scan_" in glue
    assert "verify_ros1::OutPort<msg::Velocity, ::geometry_msgs::Twist> port_navvel_" in glue
    assert "static_assert(std::is_same<verify_gen::msg::LaserScan, ::sensor_msgs::LaserScan>::value," in glue
    cmake = files["CMakeLists.txt"]
    assert "find_path(VERIFY_MSG_sensor_msgs sensor_msgs/LaserScan.h REQUIRED)" in cmake
    assert "${VERIFY_MSG_nav_msgs}" in cmake and "find_package(nav_msgs" not in cmake  # (its config needs catkin)
    assert all(f"<depend>{p}</depend>" in files["package.xml"] for p in ("geometry_msgs", "nav_msgs", "sensor_msgs"))
    params = files["config/parameters.yaml"]
    assert '    sources:  # the node of the model that writes it (its messages carry records)\n      "odom": ' \
           '"/Navigation/base"' in params


def test_an_unbound_type_stays_bytes_on_the_wire():
    files = _generated(NAVIGATION / "navigation.vfy")
    assert "using LaserScan = std::vector<std::uint8_t>;" in files["user/types/LaserScan.hpp"]
    glue = files["glue/ObstacleAvoidance.hpp"]
    assert "verify_ros1::InPort<msg::LaserScan, verify_ros1::Bytes> port_scan_" in glue
    assert "static_assert" not in glue and "VERIFY_MSG" not in files["CMakeLists.txt"]


def test_binding_a_type_changes_no_other_file_than_its_users(tmp_path):
    """Only the glue of the components that use the type, the build and the new type header differ."""
    plain = _generated(NAVIGATION / "navigation.vfy")
    (tmp_path / "components.vfy").write_text((NAVIGATION / "components.vfy").read_text(encoding="utf-8"))
    text = (NAVIGATION / "navigation.vfy").read_text(encoding="utf-8")
    (tmp_path / "navigation.vfy").write_text(text + 'message GridMap = ros "nav_msgs/OccupancyGrid"\n')
    bound = _generated(tmp_path / "navigation.vfy")
    changed = {p for p in plain if plain[p] != bound[p]}
    assert changed == {"CMakeLists.txt", "package.xml", "glue/Mapper.hpp", "glue/Planner.hpp", "user/types/GridMap.hpp"}


@pytest.mark.slow
def test_a_user_header_that_no_longer_names_the_bound_message_stops_the_build(tmp_path, capsys):
    """A type header written before the type was bound (bytes) is the user's and stays; the glue's
    compile-time check says what to do instead of letting the nodes send bytes where a message is due."""
    import subprocess

    from .conftest import in_ci

    if shutil.which("g++") is None or not Path("/usr/include/sensor_msgs/LaserScan.h").is_file():
        if in_ci():
            pytest.fail("g++ or ROS 1's sensor_msgs missing (scripts/install-tools installs them)")
        pytest.skip("g++ or ROS 1's sensor_msgs missing")
    project = tmp_path / "out"
    assert main(["gen", "ros1", str(NAVIGATION / "navigation-ros.vfy"), "-o", str(project)]) == 0
    header = project / "user" / "types" / "LaserScan.hpp"
    header.write_text(_generated(NAVIGATION / "navigation.vfy")["user/types/LaserScan.hpp"], encoding="utf-8")

    def syntax_check() -> subprocess.CompletedProcess[str]:
        return subprocess.run(["g++", "-std=c++17", "-fsyntax-only", f"-I{project / 'include'}", f"-I{project}",
                               f"-I{project / 'user'}", str(project / "glue" / "Laser_main.cpp")],
                              capture_output=True, text=True, timeout=600)

    stale = syntax_check()
    assert stale.returncode != 0
    assert ("message type LaserScan is bound to sensor_msgs/LaserScan in the model: user/types/LaserScan.hpp "
            "must name it (delete the file and regenerate)") in stale.stderr
    header.unlink()
    assert main(["gen", "ros1", str(NAVIGATION / "navigation-ros.vfy"), "-o", str(project)]) == 0
    assert syntax_check().returncode == 0, "regenerated, the header names the message"
