"""`verify trace` (specs/trace.md) on a real trace CARET recorded (tests/data/caret-traces/, with its
origin and licence) and on job records with known answers."""
from __future__ import annotations

import json
import shutil
from fractions import Fraction
from pathlib import Path

import pytest

import verify
from verify.cli import main

from .builders import traced
from .conftest import EXAMPLES, in_ci

TRACE = Path(__file__).parent / "data" / "caret-traces" / "talker_listener"
COMPLETED = EXAMPLES / "caret-talker-listener" / "completed.vfy"


def require_bindings() -> None:
    from verify.trace import lttng

    try:
        lttng.bindings()
    except lttng.Unavailable:
        if in_ci():
            raise
        pytest.skip("babeltrace2's Python bindings are not installed (scripts/install-tools)")


def test_the_caret_trace_gives_the_talkers_period_and_each_callbacks_execution_times():
    require_bindings()
    result = traced(COMPLETED, [str(TRACE)])
    assert result.matching.pairs.keys() == {"talker.timer_callback_0", "listener.subscription_callback_0"}
    assert result.matching.callbacks_left_out == 2  # (the nodes' /parameter_events subscriptions, as in CARET)
    talker = result.measured.task("talker.timer_callback_0")
    listener = result.measured.task("listener.subscription_callback_0")
    assert talker is not None and listener is not None
    assert talker.configured_period == 1 and talker.jobs == 5 and listener.jobs == 5
    # the talker's callback_start/callback_end pairs of the trace (babeltrace2 prints them): ns exact
    assert talker.execution is not None and talker.execution.max == Fraction(783352, 10**9)
    assert talker.execution.min == Fraction(329575, 10**9)
    assert listener.execution is not None and listener.execution.max == Fraction(459751, 10**9)
    assert talker.mean_period is not None and abs(talker.mean_period - 1) < Fraction(1, 1000)
    codes = sorted(d.code for d in result.diagnostics)
    assert codes.count("E801") == 2  # both callbacks ran longer than the guessed wcets of completed.vfy
    chain = result.measured.chains[0]
    assert chain.data_age is not None and chain.data_age.max < Fraction(5, 1000)  # its spec holds
    assert chain.reaction_time is not None and chain.reaction_time.max < Fraction(1010, 1000)


def test_the_command_reports_and_calibrates_the_caret_trace(tmp_path, capsys):
    require_bindings()
    model = tmp_path / "completed.vfy"
    shutil.copy(COMPLETED, model)
    assert main(["trace", str(model), str(TRACE)]) == 1  # (E801: above the wcet)
    out, err = capsys.readouterr()
    assert "timer callback (period 1 s) of node `/talker`" in out and "error[E801]" in err
    assert ("  talker.chatter -> listener.chatter: 5 messages, 363.889 us / 410.846 us / 681.328 us / 681.328 us in "
            "[0 ms, 0 ms] above the delay\n") in out and "warning[E807]" in err
    assert main(["trace", str(model), str(TRACE), "--format", "json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "verify.trace/1" and {t["task"] for t in doc["tasks"]} == {
        "talker.timer_callback_0", "listener.subscription_callback_0"}
    assert doc["connections"] == [{"connection": "talker.chatter -> listener.chatter", "topics": ["/chatter"],
                                   "delay": {"count": 5, "min_s": "363889/1000000000", "p50_s": "205423/500000000",
                                             "p99_s": "42583/62500000", "max_s": "42583/62500000"},
                                   "delay_min_s": "0", "delay_max_s": "0"}]  # (681.328 us = 42583/62500000 s)
    assert main(["trace", str(model), str(TRACE), "--format", "sarif"]) == 1
    sarif = json.loads(capsys.readouterr().out)
    assert sarif["version"] == "2.1.0" and "E807" in {r["ruleId"] for r in sarif["runs"][0]["results"]}
    before = model.read_text(encoding="utf-8")
    assert main(["trace", str(model), str(TRACE), "--calibrate", "--diff"]) == 0
    diff = capsys.readouterr().out
    assert "-    wcet 200 us  // completed\n" in diff and "+    wcet 941 us  // completed\n" in diff  # 783 us + 20 %
    assert "+    bcet 329 us  // completed\n" in diff  # 329.575 us, down
    # the /chatter delays, 363.889 us .. 681.328 us: down, and up after 20 %
    assert "+  connect talker.chatter -> listener.chatter delay 363 us .. 818 us\n" in diff
    assert model.read_text(encoding="utf-8") == before  # (--diff writes nothing)
    assert main(["trace", str(model), str(TRACE), "--calibrate", "--in-place"]) == 0
    capsys.readouterr()
    assert main(["trace", str(model), str(TRACE)]) == 0  # calibrated: the measurements agree with the model
    err = capsys.readouterr().err
    assert "E801" not in err and "E807" not in err


#: the /chatter messages of the CARET trace, publish (`rcl_publish` of the /chatter publisher) to receipt
#: (the listener's `dispatch_subscription_callback` with the source stamp `dds_bind_addr_to_stamp` bound
#: to the published message), read by hand from babeltrace2's text: 05:29:52.288811360 published,
#: stamp 1631078992288815446, dispatched 05:29:52.289222206 (410.846 us); in order of receipt
CHATTER_DELAYS_NS = [681328, 363889, 410846, 400715, 481753]


def test_the_caret_trace_links_each_chatter_message_to_its_receipt():
    require_bindings()
    result = traced(COMPLETED, [str(TRACE)])
    ((key, link),) = result.recording.links.items()  # (/parameter_events and /rosout are left out)
    assert key == ("/chatter", "/talker", "/listener") and list(link.delays) == CHATTER_DELAYS_NS
    assert not result.recording.partial
    (c,) = result.delays.connections
    assert c.connection == "talker.chatter -> listener.chatter" and c.topics == ("/chatter",)
    assert (c.delays.count, c.delays.min, c.delays.p50, c.delays.max) == (
        5, Fraction(363889, 10**9), Fraction(410846, 10**9), Fraction(681328, 10**9))
    # completed.vfy gives the connection no delay: every message took longer than the 0 it assumes
    (found,) = [d for d in result.diagnostics if d.code == "E807"]
    assert found.severity.value == "warning" and found.span.line == 33 and "681.328 us" in found.message
    # and the chain's alarms name it among the assumptions that broke
    alarms = [d.message for d in result.diagnostics if d.code == "E803"]
    assert alarms and all("a message of `talker.chatter -> listener.chatter` took 681.328 us, above its delay 0 ms"
                          in m for m in alarms)


def test_calibrating_replaces_a_delay_in_place_and_keeps_its_comment(tmp_path, capsys):
    require_bindings()
    model = tmp_path / "m.vfy"
    connect = "connect talker.chatter -> listener.chatter"
    model.write_text(COMPLETED.read_text(encoding="utf-8").replace(connect, connect + " delay 1 ms  // guess"),
                     encoding="utf-8")
    assert main(["trace", str(model), str(TRACE)]) == 1  # (E801)
    err = capsys.readouterr().err  # (`delay 1 ms` is 1 ms exactly: every message was faster, none slower)
    assert ("warning[E807]: connection `talker.chatter -> listener.chatter`: a message took only 363.889 us from "
            "its publish to its receipt in the trace, below its delay's minimum 1 ms") in err
    assert err.count("[E807]") == 1
    assert main(["trace", str(model), str(TRACE), "--calibrate", "--margin", "0", "--in-place"]) == 0
    assert ("connection talker.chatter -> listener.chatter: delay 1 ms -> 363 us .. 682 us"
            in capsys.readouterr().err)
    text = model.read_text(encoding="utf-8")
    assert "  connect talker.chatter -> listener.chatter delay 363 us .. 682 us  // guess\n" in text
    assert main(["trace", str(model), str(TRACE)]) == 0


def _linking_reader(take: bool, dispatch: bool):
    """A talker publishing /chatter and a listener subscribed to it, registered as ros2_tracing and CARET
    record them (handles are made up)."""
    from verify.trace.lttng_events import Reader

    reader = Reader()
    talker, listener = reader.process(1), reader.process(2)
    reader.on_rcl_node_init(talker, 0, 1, 0x10, "talker", "/")
    reader.on_rcl_publisher_init(talker, 0, 1, 0x11, 0x10, "/chatter")
    reader.on_rcl_node_init(listener, 0, 2, 0x20, "listener", "/")
    reader.on_rcl_subscription_init(listener, 0, 2, 0x21, 0x20, 0x22, "/chatter")
    reader.on_rclcpp_subscription_init(listener, 0, 2, 0x21, 0x23)
    reader.on_rclcpp_subscription_callback_added(listener, 0, 2, 0x23, 0x24)

    def message(published: int, stamp: int, received: int | None) -> None:
        reader.on_rcl_publish(talker, published, 1, 0x11, 0x99)
        reader.on_rmw_publish(talker, published + 5, 1, 0x99, stamp)
        if received is not None and take:
            reader.on_rmw_take(listener, received, 2, 0x22, stamp, 1)
        if received is not None and dispatch:
            reader.on_dispatch_subscription_callback(listener, received + 7, 2, 0x24, stamp)

    return reader, message


@pytest.mark.parametrize("take, dispatch", [(True, False), (False, True), (True, True)])
def test_a_receipt_is_linked_to_its_publish_by_the_source_timestamp(take, dispatch):
    reader, message = _linking_reader(take, dispatch)
    message(1000, 77, 1300)
    message(2000, 78, 2100)
    recording = reader.recording(("t",))
    link = recording.links[("/chatter", "/talker", "/listener")]
    first = 0 if take else 7  # (rmw_take and the dispatch of one message: one receipt, the first)
    assert list(link.delays) == [300 + first, 100 + first] and not recording.partial


def test_a_receipt_without_its_publish_and_a_publish_never_received_are_counted_as_partial():
    reader, message = _linking_reader(True, False)
    reader.on_rmw_take(reader.process(2), 500, 2, 0x22, 11, 1)  # (published before the trace began)
    message(1000, 77, 1300)
    message(2000, 78, None)  # (lost)
    message(3000, 79, 3200)
    message(4000, 80, None)  # (on its way when the trace ended: not counted)
    recording = reader.recording(("t",))
    assert list(recording.links[("/chatter", "/talker", "/listener")].delays) == [300, 200]
    assert recording.partial == [
        "message(s) published and not received by any subscription in the trace (lost, or received without a "
        "trace event): 1 of `/chatter`",
        "message(s) received without their publish in the trace (published before it began, or by a process not "
        "traced): 1 of `/chatter`"]


def test_publishes_given_up_count_as_lost_only_when_later_ones_were_received(monkeypatch):
    from verify.trace import links

    monkeypatch.setattr(links, "WINDOW", 2)
    reader, message = _linking_reader(True, False)
    for k in range(5):  # (no receipt at all: the subscriber's takes are not traced, say)
        message(1000 * k, 70 + k, None)
    assert reader.recording(("t",)).partial == []
    reader, message = _linking_reader(True, False)
    message(0, 60, 100)
    for k in range(1, 5):  # (lost, all but the last two given up; then one more received)
        message(1000 * k, 70 + k, None)
    message(9000, 99, 9100)
    assert reader.recording(("t",)).partial == [
        "message(s) published and not received by any subscription in the trace (lost, or received without a "
        "trace event): 4 of `/chatter`"]


def test_receipts_of_a_topic_whose_publishes_carry_no_source_timestamp_are_no_partial_trace():
    """ros2_tracing before Jazzy: `rmw_publish` without its `timestamp` (ignored), `rmw_take` with one."""
    reader, _ = _linking_reader(True, False)
    talker, listener = reader.process(1), reader.process(2)
    for k in range(3):
        reader.on_rcl_publish(talker, 1000 * k, 1, 0x11, 0x99)
        reader.on_rmw_take(listener, 1000 * k + 300, 2, 0x22, 50 + k, 1)
    recording = reader.recording(("t",))
    assert recording.links == {} and recording.partial == []


def _intra_reader(stamped: bool = True):
    """A talker and a listener in one process, /chatter delivered intra-process as rclcpp and CARET record
    it: the subscription's intra-process waitable registered as a second rclcpp subscription of its rcl
    handle, with a callback of its own (handles are made up)."""
    from verify.trace.lttng_events import Reader

    reader = Reader()
    p = reader.process(1)
    reader.on_rcl_node_init(p, 0, 1, 0x10, "talker", "/")
    reader.on_rcl_publisher_init(p, 0, 1, 0x11, 0x10, "/chatter")
    reader.on_rcl_node_init(p, 0, 1, 0x20, "listener", "/")
    reader.on_rcl_subscription_init(p, 0, 1, 0x21, 0x20, 0x22, "/chatter")
    reader.on_rclcpp_subscription_callback_added(p, 0, 1, 0x25, 0x26)  # (the waitable's, before its init)
    reader.on_rclcpp_subscription_init(p, 0, 1, 0x21, 0x25)
    reader.on_rclcpp_subscription_init(p, 0, 1, 0x21, 0x23)
    reader.on_rclcpp_subscription_callback_added(p, 0, 1, 0x23, 0x24)

    def message(published: int, address: int, stamp: int, received: int | None) -> None:
        reader.on_rclcpp_intra_publish(p, published, 1, 0x11, address, stamp if stamped else None)
        if received is not None:
            reader.on_dispatch_intra_process_subscription_callback(p, received, 1, 0x26, address, stamp)

    return reader, message


@pytest.mark.parametrize("stamped", [True, False])
def test_an_intra_process_receipt_is_linked_to_its_publish_by_message_address_and_timestamp(stamped):
    reader, message = _intra_reader(stamped)
    message(1000, 0x99, 5, 1400)
    message(2000, 0x99, 6, 2250)  # (the address used again)
    message(3000, 0x98, 7, 3100)
    recording = reader.recording(("t",))
    assert list(recording.links[("/chatter", "/talker", "/listener")].delays) == [400, 250, 100]
    assert recording.partial == []


def test_an_intra_process_receipt_without_its_publish_is_counted_as_partial():
    reader, message = _intra_reader()
    p = reader.process(1)
    reader.on_dispatch_intra_process_subscription_callback(p, 500, 1, 0x26, 0x97, 4)  # (published before)
    message(1000, 0x99, 5, 1400)
    message(2000, 0x99, 6, None)  # (lost: its address used again by a message received)
    message(3000, 0x99, 7, 3300)
    reader.on_dispatch_intra_process_subscription_callback(p, 3500, 1, 0x26, 0x99, 8)  # (another timestamp)
    recording = reader.recording(("t",))
    assert list(recording.links[("/chatter", "/talker", "/listener")].delays) == [400, 300]
    assert recording.partial == [
        "intra-process message(s) published and not received by any subscription in the trace (lost, or received "
        "without a trace event): 1 of `/chatter`",
        "intra-process message(s) received without their publish in the trace (published before it began, or by a "
        "process not traced): 2 of `/chatter`"]


def test_a_subscriptions_intra_process_callback_is_one_callback_with_it():
    """As CARET identifies it: the jobs of both callbacks of one subscription (inter- and intra-process) are
    the jobs of one subscription callback."""
    reader, _ = _intra_reader()
    p = reader.process(1)
    for callback, start in ((0x24, 100), (0x26, 300), (0x24, 500)):
        reader.on_callback_start(p, start, 1, callback)
        reader.on_callback_end(p, start + 50, 1, callback)
    recording = reader.recording(("t",))
    (key,) = recording.callbacks
    assert recording.callbacks[key].topic == "/chatter" and list(recording.jobs[key].starts) == [100, 300, 500]


def test_an_optional_field_reads_none_when_the_event_has_not_got_it():
    """ros2_tracing's `rclcpp_intra_publish` has no `message_timestamp`, CARET's has: both are read."""
    from verify.trace.lttng_graph import payload_member
    from verify.trace.lttng_events import USED

    assert "?message_timestamp" in USED["ros2:rclcpp_intra_publish"]
    _, getter = payload_member({"publisher_handle": (0, int), "message": (1, int)}, "?message_timestamp")
    assert getter is not None and getter("any member") is None
    assert payload_member({"message_timestamp": (2, int)}, "?message_timestamp") == (2, int)
    assert payload_member({}, "message") == (0, None)  # (a field required: the event is not read without it)


def test_intra_process_publishes_without_any_intra_process_receipt_are_no_partial_trace():
    """ros2_tracing without CARET: `rclcpp_intra_publish` recorded, no receipt event to link it to."""
    reader, message = _intra_reader(stamped=False)
    for k in range(3):
        message(1000 * k, 0x99, k, None)
    recording = reader.recording(("t",))
    assert recording.links == {} and recording.partial == []


def test_a_link_of_nodes_the_model_does_not_connect_is_listed_not_guessed():
    from verify.trace.delays import measure_delays

    reader, message = _linking_reader(True, False)
    message(1000, 77, 1300)
    loaded = verify.load(str(COMPLETED))
    model = loaded.system(None)
    recording = reader.recording(("t",))
    assert measure_delays(model, recording).connections[0].delays.max == Fraction(300, 10**9)
    other = verify.load_text(MODEL, "m.vfy").system(None)
    delays = measure_delays(other, recording)
    assert delays.connections == () and delays.unpaired == (
        ("`/chatter` from node `/talker` to node `/listener` (1 messages)",
         "the model has no connection from an instance `talker` to an instance `listener`"),)


IMPORTED = EXAMPLES / "caret-talker-listener" / "imported.vfy"


def test_a_model_without_wcets_as_imported_is_calibrated_and_keeps_its_other_gaps(tmp_path, capsys):
    """`verify import caret` writes no wcet, priority or core: the model does not load (E217, E213,
    E214), yet a trace calibrates it — through a stand-in that fills those gaps to pair and measure."""
    require_bindings()
    assert main(["trace", str(IMPORTED), str(TRACE)]) == 2  # (not calibrating: it does not load)
    assert "error[E217]" in capsys.readouterr().err
    out = tmp_path / "calibrated.vfy"
    assert main(["trace", str(IMPORTED), str(TRACE), "--calibrate", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "Talker.timer_callback_0: wcet (none) -> 941 us" in err and "E213, E214" in err
    text = out.read_text(encoding="utf-8")
    assert ("    produces chatter\n    bcet 329 us  // measured\n    wcet 941 us  // measured\n  }\n" in text
            and "    reads chatter\n    bcet 157 us  // measured\n    wcet 552 us  // measured\n  }\n" in text)
    assert "  connect talker.chatter -> listener.chatter delay 363 us .. 818 us\n" in text
    before = IMPORTED.read_text(encoding="utf-8")
    assert text.count("\n") == before.count("\n") + 4 and "priority 1" not in text and "calibration_core" not in text
    again = verify.load(str(out))
    assert {d.code for d in again.diagnostics if d.severity.value == "error"} == {"E213", "E214"}


def test_the_stand_in_fills_every_gap_and_nothing_else():
    from verify.core.diagnostics import DiagnosticSink as Sink
    from verify.core.source import SourceFile
    from verify.frontend.parse import parse_text
    from verify.trace.standin import only_gaps, stand_in_text

    text = ("component C {\n  task T {\n    bcet 2 ms\n  }\n  task U { }\n}\n"
            "system S {\n  core calibration_core\n  executor e single_threaded on calibration_core priority 1\n"
            "  instance a : C {\n    task T timer 10 ms\n    task U executor e timer 20 ms\n  }\n}\n")
    assert only_gaps(verify.load_text(text, "m.vfy").diagnostics)
    module = parse_text(text, "m.vfy", Sink())
    filled = stand_in_text(module, SourceFile("m.vfy", text))
    assert "task T { wcet 2 ms }" not in filled and "    bcet 2 ms\n   wcet 2 ms }" in filled  # (T's bcet)
    assert "task U {  wcet 1 us }" in filled  # (U on one line)
    assert "system S { core calibration_core2 \n" in filled and "task T priority 1 on calibration_core2 timer" in filled
    assert "task U executor e timer 20 ms" in filled  # (a callback needs neither)
    assert verify.load_text(filled, "m.vfy").ok


def test_a_model_with_other_errors_is_not_calibrated(tmp_path, capsys):
    require_bindings()
    model = tmp_path / "m.vfy"
    model.write_text(IMPORTED.read_text(encoding="utf-8").replace("reads chatter", "reads chatterx"), encoding="utf-8")
    assert main(["trace", str(model), str(TRACE), "--calibrate", "--in-place"]) == 2
    assert "chatterx" in capsys.readouterr().err
    assert "chatterx" in model.read_text(encoding="utf-8") and "measured" not in model.read_text(encoding="utf-8")


# ------------------------------------------------------------------ job records: known answers

MODEL = """\
component C {
  task T {
    bcet 1 ms  // kept
    wcet 2 ms
  }
}

system S {
  core cpu0
  instance c : C on cpu0 {
    task T priority 1 timer 10 ms
  }
}
"""


def _records(path: Path, times_us: list[int]) -> None:
    lines = [json.dumps({"node": "/S/c", "task": "T", "seq": k, "release": k * 10_000_000,
                         "start": k * 10_000_000, "finish": k * 10_000_000 + us * 1000})
             for k, us in enumerate(times_us)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def test_burned_times_calibrate_to_those_times(tmp_path, capsys):
    model, jobs = tmp_path / "m.vfy", tmp_path / "jobs.jsonl"
    model.write_text(MODEL, encoding="utf-8")
    _records(jobs, [1200, 1500, 1800, 1300])
    assert main(["trace", str(model), str(jobs), "--calibrate", "--margin", "0", "-o", str(tmp_path / "out.vfy")]) == 0
    written = (tmp_path / "out.vfy").read_text(encoding="utf-8")
    assert "    bcet 1200 us  // kept\n    wcet 1800 us\n" in written
    assert written.replace("1200 us", "1 ms").replace("1800 us", "2 ms") == MODEL  # only the values changed


def test_one_overrun_job_gives_exactly_one_located_error(tmp_path, capsys):
    model, jobs = tmp_path / "m.vfy", tmp_path / "jobs.jsonl"
    model.write_text(MODEL, encoding="utf-8")
    _records(jobs, [1500] * 20 + [2500] + [1500] * 20)
    assert main(["trace", str(model), str(jobs)]) == 1
    err = capsys.readouterr().err
    assert err.count("error[") == 1 and "error[E801]" in err and "m.vfy:4:10" in err
    assert "1 of 41 jobs above the wcet: job 21: 2.5 ms" in err


def test_a_chain_recomputed_from_job_records_follows_timing_section_4(tmp_path):
    """A sensor every 10 ms, a controller triggered 1 ms after each publish: data age = finish − the
    sensor job's start; reaction time per sensor read s_j: the first end holding s_j, minus s_(j−1)."""
    text = (Path(__file__).parent.parent / "specs" / "diagnostics.md").read_text(encoding="utf-8")
    model_text = text.split("## E804")[1].split("```vfy command=trace\n")[1].split("```")[0]
    model = tmp_path / "m.vfy"
    model.write_text(model_text.replace("data_age <= 5 ms", "data_age <= 50 ms"), encoding="utf-8")
    jobs = []
    for k in range(5):
        t = k * 10_000_000
        jobs.append({"node": "/Loop/sensor", "task": "Sample", "release": t, "start": t, "finish": t + 1_000_000})
        jobs.append({"node": "/Loop/control", "task": "Step", "release": t + 1_000_000, "start": t + 2_000_000,
                     "finish": t + 3_000_000})
    path = tmp_path / "jobs.jsonl"
    path.write_text("".join(json.dumps(j) + "\n" for j in jobs), encoding="utf-8")
    result = traced(model, [str(path)])
    chain = result.measured.chains[0]
    assert chain.data_age is not None and chain.data_age.min == chain.data_age.max == Fraction(3, 1000)
    assert chain.reaction_time is not None and chain.reaction_time.max == Fraction(13, 1000)
    assert chain.reaction_time.count == 4


# ------------------------------------------------------------------ bad input: never a traceback

def test_a_truncated_trace_is_read_in_part_or_refused_never_a_traceback(tmp_path, capsys):
    require_bindings()
    broken = tmp_path / "trace"
    shutil.copytree(TRACE, broken)
    streams = sorted(p for p in broken.rglob("ros2_*") if p.is_file() and p.parent.name == "64-bit")
    biggest = max(streams, key=lambda p: p.stat().st_size)
    data = biggest.read_bytes()
    biggest.write_bytes(data[: len(data) // 2 + 7])
    code = main(["trace", str(COMPLETED), str(broken)])
    err = capsys.readouterr().err
    assert "Traceback" not in err and code in (0, 1, 2)
    assert "E806" in err  # (read in part: a warning; or not read: an error)


@pytest.mark.parametrize("what", ["empty-dir", "not-ctf", "missing"])
def test_what_is_no_trace_is_e806(tmp_path, capsys, what):
    target = tmp_path / "t"
    if what == "empty-dir":
        target.mkdir()
    elif what == "not-ctf":
        target.mkdir()
        (target / "metadata").write_bytes(b"\x00garbage" * 100)
    if what != "missing":
        require_bindings()
    assert main(["trace", str(COMPLETED), str(target)]) == 2
    err = capsys.readouterr().err
    assert "error[E806]" in err and "Traceback" not in err


def test_another_systems_trace_pairs_nothing_and_lists_it(tmp_path, capsys):
    require_bindings()
    other = tmp_path / "other.vfy"
    other.write_text(MODEL, encoding="utf-8")
    assert main(["trace", str(other), str(TRACE)]) == 0
    err = capsys.readouterr().err
    assert "warning[E805]: task `c.T` is not found in the trace" in err
    assert "the model has no instance `talker`" in err


@pytest.mark.parametrize("name, said", [("missing.jsonl", "there is no such file"),
                                        ("/dev/null", "it is not a regular file"),
                                        ("junk.jsonl", "no job record in")])
def test_a_file_that_is_no_job_records_is_e806(tmp_path, capsys, name, said):
    (tmp_path / "junk.jsonl").write_bytes(b'{"node": "/S/c", "task": "T", "start": 5, "finish": 3}\n\xff\x00[1]\n')
    path = name if name.startswith("/") else str(tmp_path / name)
    assert main(["trace", str(COMPLETED), path]) == 2
    err = capsys.readouterr().err
    assert "error[E806]" in err and said in err and "Traceback" not in err


def test_lines_that_are_no_records_leave_a_partial_recording(tmp_path, capsys):
    model, jobs = tmp_path / "m.vfy", tmp_path / "jobs.jsonl"
    model.write_text(MODEL, encoding="utf-8")
    _records(jobs, [1500, 1500])
    with jobs.open("a", encoding="utf-8") as fh:
        fh.write('{"topic": "/other", "data": "x"}\nnot json\n')
    assert main(["trace", str(model), str(jobs)]) == 0
    out, err = capsys.readouterr()
    assert "PARTIAL: 1 line(s) are not job records" in out and "warning[E806]" in err and "jobs.jsonl:4" in err


def test_a_callback_running_on_two_threads_at_once_gives_two_jobs_in_start_order():
    """A callback of a reentrant group: its jobs on two threads overlap; each end closes its thread's job."""
    from verify.trace.lttng_events import Reader

    reader = Reader()
    p = reader.process(7)
    reader.on_rcl_node_init(p, 0, 1, 0x10, "n", "/")
    reader.on_rcl_timer_init(p, 0, 1, 0x20, 5_000_000)
    reader.on_rclcpp_timer_callback_added(p, 0, 1, 0x20, 0x30)
    reader.on_rclcpp_timer_link_node(p, 0, 1, 0x20, 0x10)
    reader.on_callback_start(p, 100, 1, 0x30)
    reader.on_callback_start(p, 200, 2, 0x30)
    reader.on_rcl_publish(p, 250, 2, 0x40, 0x50)
    reader.on_callback_end(p, 400, 2, 0x30)
    reader.on_callback_end(p, 500, 1, 0x30)
    recording = reader.recording(("t",))
    (key,) = recording.callbacks
    jobs = recording.jobs[key]
    assert (list(jobs.starts), list(jobs.ends), list(jobs.writes)) == ([100, 200], [500, 400], [500, 250])
    assert recording.callbacks[key].node == "/n" and recording.callbacks[key].period_ns == 5_000_000


def test_a_timer_registered_with_another_period_is_paired_and_e802(tmp_path, capsys):
    require_bindings()
    text = COMPLETED.read_text(encoding="utf-8").replace("timer 1 s", "timer 500 ms")
    model = tmp_path / "m.vfy"
    model.write_text(text, encoding="utf-8")
    assert main(["trace", str(model), str(TRACE)]) == 1
    err = capsys.readouterr().err
    # one timer on each side: paired, and its period is off the model
    assert "error[E802]: the timer of `talker.timer_callback_0` has the period 1 s in the trace, not 500 ms" in err
