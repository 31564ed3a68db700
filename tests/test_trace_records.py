"""`verify trace` on the generated nodes' job records in both formats (specs/trace.md §1.2, §3): the ROS 2
nodes' (``TRACE_DIR/UNIT.jsonl``, a directory or its files), the ROS 1 nodes' (``/verify/jobs``), with and
without what each job read. Known answers: a reader job that starts while the newer message is still on
its way read the older one; its record says so, and the data age is that of the job it read."""
from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest

from verify.cli import main

from .builders import traced

MS = 1_000_000
SPECS = Path(__file__).parent.parent / "specs" / "diagnostics.md"


@pytest.fixture
def model(tmp_path: Path) -> Path:
    """The sensor → control loop of specs/diagnostics.md (E804), with a data-age spec it meets."""
    text = SPECS.read_text(encoding="utf-8").split("## E804")[1].split("```vfy command=trace\n")[1].split("```")[0]
    path = tmp_path / "loop.vfy"
    path.write_text(text.replace("data_age <= 5 ms", "data_age <= 50 ms"), encoding="utf-8")
    return path


def _loop_jobs(n: int = 5, step: int = MS, cpu: tuple[int, int] | None = None) -> list[tuple[dict, dict]]:
    """(sensor job, control job) k = 1..n: the sensor every 10 ms for 1 ms; the control starts 1.5 ms after
    the sensor's start, 0.5 ms after its publish, while that message is still on its way (2 ms): it
    reads the sensor's previous job (none the first time); it ends ``step`` after its start. ``cpu``:
    the CPU time each job's thread spent (sensor, control), in every record; None: no record says."""
    out = []
    for k in range(1, n + 1):
        t = (k - 1) * 10 * MS
        times = {"cpu": cpu[0]} if cpu else {}
        sensor = {"seq": k, "release": t, "start": t, "finish": t + MS, **times}
        times = {"cpu": cpu[1]} if cpu else {}
        control = {"seq": k, "release": t + MS, "start": t + 3 * MS // 2, "finish": t + 3 * MS // 2 + step,
                   "read": k - 1, **times}
        out.append((sensor, control))
    return out


def _ros2(directory: Path, reads: bool = True, **jobs: Any) -> Path:
    """The loop's jobs (``_loop_jobs(**jobs)``) as the ROS 2 nodes write them: one file per process."""
    directory.mkdir(exist_ok=True)
    sensor, control = [], []
    for s, c in _loop_jobs(**jobs):
        sensor.append({"unit": "sensor_Sample", "task": "sensor.Sample", "event": s["seq"],
                       "writes": {"data": s["seq"]}, "reads": {}, "stamps": [], **s})
        job = {"unit": "control_Step", "task": "control.Step", "event": c["seq"], "writes": {}, "stamps": [],
               **{k: v for k, v in c.items() if k != "read"}}
        if reads:
            job["reads"] = {"data": ["sensor_Sample", "sensor.Sample", c["read"], c["read"]] if c["read"] else None}
        control.append(job)
    for name, jobs in (("sensor_Sample", sensor), ("control_Step", control)):
        (directory / f"{name}.jsonl").write_text("".join(json.dumps(j) + "\n" for j in jobs), encoding="utf-8")
    return directory


def _ros1(path: Path, reads: bool = True, **jobs: Any) -> Path:
    """The loop's jobs (``_loop_jobs(**jobs)``) as a recorder of the ROS 1 nodes' /verify/jobs writes them
    (a port without a value is not among the reads)."""
    lines = []
    for s, c in _loop_jobs(**jobs):
        lines.append({"node": "/Loop/sensor", "task": "Sample", "reads": {}, **s})
        job = {"node": "/Loop/control", "task": "Step", **{k: v for k, v in c.items() if k != "read"}}
        if reads:
            job["reads"] = {"data": c["read"]} if c["read"] else {}
        lines.append(job)
    path.write_text("".join(json.dumps({"topic": "/verify/jobs", "data": json.dumps(j)}) + "\n" for j in lines),
                    encoding="utf-8")
    return path


def _chain(result):
    (chain,) = result.measured.chains
    assert chain.data_age is not None and chain.reaction_time is not None
    return chain


def _recorded_reads_answer(result) -> None:
    """What the reads give: control job k ≥ 2 holds sensor job k − 1's start (10 ms before its own
    sensor's), data age 12.5 ms; one reaction per new stamp, each 22.5 ms (from the stamp before)."""
    chain = _chain(result)
    assert (chain.data_age.count, chain.data_age.min, chain.data_age.max) == (4, Fraction(25, 2000), Fraction(25, 2000))
    assert (chain.reaction_time.count, chain.reaction_time.min, chain.reaction_time.max) == (
        3, Fraction(45, 2000), Fraction(45, 2000))
    assert chain.jitter == 0


def test_ros2_records_pair_by_process_and_task_and_their_reads_give_the_data_age(model, tmp_path):
    result = traced(model, [str(p) for p in sorted(_ros2(tmp_path / "trace").glob("*.jsonl"))])
    assert result.matching.pairs == {"sensor.Sample": "sensor_Sample\tsensor.Sample",
                                     "control.Step": "control_Step\tcontrol.Step"}
    assert not result.matching.tasks_unmatched and not result.matching.callbacks_unmatched
    step = result.measured.task("control.Step")
    assert step is not None and step.jobs == 5
    assert step.execution is not None and step.execution.max == Fraction(1, 1000)
    _recorded_reads_answer(result)


def test_ros1_records_with_their_reads_give_the_same_answer(model, tmp_path):
    _recorded_reads_answer(traced(model, [str(_ros1(tmp_path / "run.jsonl"))]))


@pytest.mark.parametrize("write", [_ros1, _ros2])
def test_records_without_reads_are_measured_by_the_write_times(model, tmp_path, write):
    """Without reads, a job is taken to hold the writer's latest job that published before it started:
    here the newer one (the message in flight is not seen): data age 2.5 ms for every control job."""
    path = write(tmp_path / ("trace" if write is _ros2 else "run.jsonl"), reads=False)
    chain = _chain(traced(model, [str(path)]))
    assert (chain.data_age.count, chain.data_age.min, chain.data_age.max) == (5, Fraction(5, 2000), Fraction(5, 2000))
    assert (chain.reaction_time.count, chain.reaction_time.max) == (4, Fraction(25, 2000))


def test_a_directory_of_ros2_records_is_read_as_its_files(model, tmp_path, capsys):
    trace = _ros2(tmp_path / "trace")
    assert main(["trace", str(model), str(trace), "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["source"] == "job records" and doc["paths"] == [str(trace / "control_Step.jsonl"),
                                                               str(trace / "sensor_Sample.jsonl")]
    assert not doc["unpaired"]["tasks"] and not doc["unpaired"]["callbacks"]
    (chain,) = doc["chains"]
    assert chain["data_age"]["max_s"] == "1/80" and chain["reaction_time"]["count"] == 3


def test_a_read_of_a_job_not_in_the_records_holds_no_stamp(model, tmp_path):
    trace = _ros2(tmp_path / "trace")
    sensor = trace / "sensor_Sample.jsonl"
    lines = sensor.read_text(encoding="utf-8").splitlines(keepends=True)
    sensor.write_text("".join(lines[:2] + lines[3:]), encoding="utf-8")  # (sensor job 3 left out)
    chain = _chain(traced(model, [str(trace)]))
    assert chain.data_age.count == 3  # (control job 4 read sensor job 3)


def test_bad_ros2_lines_leave_a_partial_recording(model, tmp_path, capsys):
    trace = _ros2(tmp_path / "trace")
    with (trace / "control_Step.jsonl").open("a", encoding="utf-8") as fh:
        fh.write('{"unit": "control_Step", "task": "control.Step", "seq": 6, "release": 1, "start": 2, "finish": 3, '
                 '"reads": {"data": ["sensor_Sample", "sensor.Sample", -1, 0]}}\n')
        fh.write('{"unit": "control_Step", "task": "control.Step", "seq": 7, "release": 1, "start": 2, "fin')
    assert main(["trace", str(model), str(trace)]) == 0
    out, err = capsys.readouterr()
    assert "PARTIAL: 2 line(s) are not job records" in out and "control_Step.jsonl:6" in out
    assert "warning[E806]" in err and "Traceback" not in err


def test_ros2_records_of_a_process_the_model_has_not_are_listed(model, tmp_path, capsys):
    trace = _ros2(tmp_path / "trace")
    (trace / "other.jsonl").write_text('{"unit": "other", "task": "x.Y", "seq": 1, "release": 0, "start": 0, '
                                       '"finish": 5}\n', encoding="utf-8")
    assert main(["trace", str(model), str(trace)]) == 0
    err = capsys.readouterr().err
    assert "warning[E805]" in err and "the model has no task `x.Y` in a node `other`" in err


def test_an_empty_directory_of_records_is_no_trace(model, tmp_path, capsys):
    trace = tmp_path / "trace"
    trace.mkdir()
    (trace / "a.jsonl").write_text("", encoding="utf-8")
    assert main(["trace", str(model), str(trace)]) == 2
    err = capsys.readouterr().err
    assert "error[E806]" in err and "no job record in" in err and "Traceback" not in err


# ------------------------------------------------------------------ execution time: the CPU time the records give

def _where(write, tmp_path: Path) -> Path:
    return tmp_path / ("trace" if write is _ros2 else "run.jsonl")


@pytest.mark.parametrize("write", [_ros1, _ros2])
def test_a_job_longer_than_its_wcet_from_start_to_finish_within_it_of_cpu_time_is_no_e801(model, tmp_path, write,
                                                                                          capsys):
    """The control's jobs take 1.5 ms from start to finish (its wcet: 1 ms) and 0.9 ms of its thread's CPU
    time: its execution time is the CPU time, within the wcet; start to finish and release to finish
    (2 ms) are reported beside it."""
    trace = write(_where(write, tmp_path), step=3 * MS // 2, cpu=(MS // 2, 9 * MS // 10))
    result = traced(model, [str(trace)])
    assert "E801" not in {d.code for d in result.diagnostics}
    step = result.measured.task("control.Step")
    assert step is not None and step.execution is not None and step.elapsed is not None and step.response
    assert (step.cpu_jobs, step.execution.min, step.execution.max) == (5, Fraction(9, 10_000), Fraction(9, 10_000))
    assert (step.elapsed.min, step.elapsed.max, step.response.max) == (Fraction(3, 2000), Fraction(3, 2000),
                                                                       Fraction(1, 500))
    assert main(["trace", str(model), str(trace), "--format", "json"]) == 0
    (task,) = (t for t in json.loads(capsys.readouterr().out)["tasks"] if t["task"] == "control.Step")
    assert (task["cpu_jobs"], task["execution"]["max_s"], task["elapsed"]["max_s"], task["response"]["max_s"]) == (
        5, "9/10000", "3/2000", "1/500")
    assert main(["trace", str(model), str(trace)]) == 0
    out = capsys.readouterr().out
    assert "execution time = the CPU time of the job's thread (5 of 5 jobs); start to finish 1.5 ms" in out


@pytest.mark.parametrize("write", [_ros1, _ros2])
def test_a_job_above_its_wcet_of_cpu_time_is_e801_at_the_wcet(model, tmp_path, write, capsys):
    """The control's jobs take 1.2 ms of CPU time within 1.5 ms from start to finish: E801 names the CPU time."""
    trace = write(_where(write, tmp_path), step=3 * MS // 2, cpu=(MS // 2, 6 * MS // 5))
    assert main(["trace", str(model), str(trace)]) == 1
    err = capsys.readouterr().err
    assert err.count("error[E801]") == 1 and "loop.vfy:15:10" in err
    assert "above its bound 2 ms — an assumption of the bound broke: task `control.Step` used 1.2 ms of CPU time" in err
    assert "task `control.Step` used up to 1.2 ms of CPU time in the trace, above its wcet 1 ms" in err
    assert "5 of 5 jobs above the wcet" in err and "(the CPU time each job's thread spent on it)" in err


def test_records_without_cpu_are_measured_from_start_to_finish_and_with_it_by_it(model, tmp_path, capsys):
    """One control record says no CPU time: its 1.5 ms from start to finish is its execution time (E801);
    the others' CPU time (0.9 ms) is theirs."""
    trace = _ros2(tmp_path / "trace", step=3 * MS // 2, cpu=(MS // 2, 9 * MS // 10))
    control = trace / "control_Step.jsonl"
    lines = control.read_text(encoding="utf-8").splitlines(keepends=True)
    third = json.loads(lines[2])
    del third["cpu"]
    control.write_text("".join(lines[:2] + [json.dumps(third) + "\n"] + lines[3:]), encoding="utf-8")
    result = traced(model, [str(trace)])
    step = result.measured.task("control.Step")
    assert step is not None and step.execution is not None and step.cpu_jobs == 4
    assert (step.execution.min, step.execution.max, step.overruns) == (Fraction(9, 10_000), Fraction(3, 2000),
                                                                       ((2, Fraction(3, 2000)),))
    (e801,) = (d for d in result.diagnostics if d.code == "E801")
    assert "ran up to 1.5 ms in the trace" in e801.message
    assert any("the CPU time its thread spent for 4 of them, end − start for the others" in n for n in e801.notes)


def test_a_latency_above_its_bound_with_every_job_within_its_cpu_time_names_the_interference(model, tmp_path):
    """The control's jobs take 1.5 ms from start to finish with 0.9 ms of CPU time (wcet 1 ms): the data age
    above the analysis' bound (E803) is blamed on what took the CPU from them, not on a wcet."""
    result = traced(model, [str(_ros2(tmp_path / "trace", step=3 * MS // 2, cpu=(MS // 2, 9 * MS // 10)))])
    alarms = [d.message for d in result.diagnostics if d.code == "E803"]
    assert alarms and all("jobs of task `control.Step` took up to 1.5 ms from start to finish, above its wcet 1 ms, "
                          "with at most 900 us of CPU time" in a for a in alarms), alarms
    assert not any("ran" in a for a in alarms)


@pytest.mark.parametrize("cpu", ['-1', '"900000"', '1.5', 'null'])
def test_a_record_whose_cpu_is_no_whole_number_of_nanoseconds_is_left_out(model, tmp_path, capsys, cpu):
    trace = _ros2(tmp_path / "trace")
    with (trace / "control_Step.jsonl").open("a", encoding="utf-8") as fh:
        fh.write('{"unit": "control_Step", "task": "control.Step", "seq": 6, "release": 1, "start": 2, "finish": 3, '
                 f'"cpu": {cpu}}}\n')
    assert main(["trace", str(model), str(trace)]) == 0
    out, err = capsys.readouterr()
    assert "PARTIAL: 1 line(s) are not job records" in out and "control_Step.jsonl:6" in out
    assert "warning[E806]" in err and "Traceback" not in err
