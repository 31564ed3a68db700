"""Message types bound to ROS messages: `message T = ros "PACKAGE/NAME"` (specs/language.md, "Message types")."""
from __future__ import annotations

import verify
from verify.model import syntax as s
from verify.core.diagnostics import DiagnosticSink
from verify.frontend.fmt import format_text
from verify.frontend.parse import fast_parser, parse_text
from verify.frontend.recovery import recover
from verify.frontend.treebuild import TreeBuilder

TEXT = """\
// the scan is the laser's own message
message LaserScan = ros "sensor_msgs/LaserScan"
component Laser {
  out scan : LaserScan
  out raw : Blob
  task LaserTask {
    produces scan, raw
    wcet 2 ms
  }
}
message Unused = ros "std_msgs/Empty"  // declared, used by no port
system S {
  core cpu
  instance laser : Laser on cpu {
    task LaserTask priority 1 timer 25 ms
  }
}
"""


def _module(text: str) -> s.Module:
    sink = DiagnosticSink()
    module = parse_text(text, "m.vfy", sink)
    assert module is not None and not sink.items
    return module


def test_a_declaration_names_the_ros_message():
    module = _module(TEXT)
    assert [(m.name.text, m.ros) for m in module.messages] == [("LaserScan", "sensor_msgs/LaserScan"),
                                                               ("Unused", "std_msgs/Empty")]
    span = module.messages[0].ros_span
    assert (span.line, span.column, span.end_column) == (2, 25, 48)


def test_the_fast_path_and_lark_build_the_same_tree():
    builder = TreeBuilder("m.vfy", DiagnosticSink())
    fast = fast_parser().parse(TEXT, builder.callbacks(fast_parser().callback_names()), builder.tokens())
    lark = recover(TEXT, "m.vfy", DiagnosticSink()).module
    assert fast == lark == _module(TEXT)


def test_one_declaration_gives_the_ros1_and_ros2_names_of_the_ports_types():
    model = verify.load_text(TEXT, "m.vfy").system()
    (scan,) = model.messages  # only the types the system's ports use
    assert (scan.name, scan.ros1, scan.ros2) == ("LaserScan", "sensor_msgs/LaserScan", "sensor_msgs/msg/LaserScan")
    assert model.message("LaserScan") == scan and model.message("Blob") is None
    ros2 = verify.load_text(TEXT.replace("sensor_msgs/LaserScan", "sensor_msgs/msg/LaserScan"), "m.vfy").system()
    assert ros2.messages == model.messages  # ROS 2's spelling means the same


def test_fmt_keeps_declarations_in_place_and_round_trips():
    text, diagnostics = format_text(TEXT)
    assert text is not None and not diagnostics
    assert 'message LaserScan = ros "sensor_msgs/LaserScan"\n\ncomponent Laser {' in text
    assert 'message Unused = ros "std_msgs/Empty"  // declared, used by no port\n\nsystem S {' in text
    assert _module(text) == _module(TEXT)
    together = 'message A = ros "a/A"\nmessage   B=ros"b/B"\n'
    assert format_text(together)[0] == 'message A = ros "a/A"\nmessage B = ros "b/B"\n'


def test_a_type_declared_twice_is_e102_and_a_bad_ros_name_e109():
    text = 'message T = ros "a/A"\nmessage T = ros "b/B"\n'
    text += "".join(f'message U{i} = ros "{bad}"\n' for i, bad in enumerate(
        ["pkg/lower", "9pkg/V", "Pkg/V", "pkg/srv/V", "pkg", "pkg/V/", "pkg/Under_score", ""]))
    result = verify.load_text(text, "m.vfy")
    got = [(d.code, d.span.line, d.span.column) for d in result.diagnostics]
    assert got == [("E102", 2, 9)] + [("E109", line, 18) for line in range(3, 11)]
