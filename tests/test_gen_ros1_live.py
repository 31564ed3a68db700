"""The generated ROS 1 nodes of the navigation example, built and run for real (issue: model to robot).

The project of examples/navigation/navigation-ros.vfy (its message types bound to ROS messages) is
generated, its skeletons filled with jobs that burn 80 % of each task's worst-case execution time of
their thread's CPU time (`burn_cpu`, the thread's CPU clock: the quantity the job records' `cpu` is), built with
CMake against Debian's ROS 1, and run for about 10 s on a private roscore with a recorder, a stock
subscriber and `rosbag record` beside it. A bag of sensor_msgs/LaserScan made here drives the obstacle
avoidance in its laser's place. From the recorded job records and messages the tests check the semantics the
analysis assumed (every k-th arrival, timer rates), that no observed latency exceeds the bound
`analyze` gives, and that the monitors' summaries agree with what was recorded. A variant whose spec
is too tight makes the monitor report the violation; it changes only the parameter file, so the
nodes are not rebuilt.
"""
from __future__ import annotations

import json
import shutil
import subprocess
from fractions import Fraction
from pathlib import Path

import pytest

import verify
from verify.cli import main
from verify.gen.ros1 import package_name
from verify.timing import analyze

from . import rosrun
from .conftest import EXAMPLES

pytestmark = [pytest.mark.slow, pytest.mark.usefixtures("live_processes_alone")]

NAVIGATION = EXAMPLES / "navigation"
MODEL = "navigation-ros.vfy"  # (its connections have the middleware's delay: TCPROS on loopback)
RUN_SECONDS = 10
#: the share of each task's WCET its functional code burns: the rest is left for the glue's own work
#: and the middleware's threads, which run above every task (specs/codegen.md, "Execution times")
BURN_SHARE = Fraction(4, 5)


def _generate(model_dir: Path, project: Path) -> int:
    return main(["gen", "ros1", str(model_dir / MODEL), "-o", str(project)])


def _model(model_dir: Path):
    return verify.load(str(model_dir / MODEL)).system(None)


def _data_topics(model) -> dict[str, str]:
    """Every out-port's topic, with the ROS type of its message (``verify_ros1::Bytes`` when unbound)."""
    out = {}
    for port in model.ports:
        if port.direction == "out":
            message = model.message(port.message_type)
            out[f"/{model.name}/{port.id.replace('.', '/')}"] = message.ros1 if message else "std_msgs/UInt8MultiArray"
    return out


def _records(live, topic: str) -> list[dict]:
    """The out-of-band records of the messages on ``topic``, as recorded (TOPIC/verify)."""
    return [rosrun.decode_record(str(r["hex"])) for r in live["records"] if r["topic"] == f"{topic}/verify"]


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    """The navigation example generated, built and run once: (model, project, records, summaries, build log)."""
    rosrun.require_ros()
    base = tmp_path_factory.mktemp("ros1")
    model_dir = base / "model"
    shutil.copytree(NAVIGATION, model_dir)
    project = base / "project"
    assert _generate(model_dir, project) == 0
    model = _model(model_dir)
    wcet = {t.name: int(t.wcet * BURN_SHARE * 1_000_000_000) for t in model.tasks}
    rosrun.burn_execution_times(project, wcet)
    oa = project / "user" / "ObstacleAvoidance.hpp"  # (says when it reads a scan that is not empty)
    oa.write_text(oa.read_text(encoding="utf-8").replace(
        f"verify_ros1::burn_cpu({wcet['OATask']});",
        f"verify_ros1::burn_cpu({wcet['OATask']});\n    if (scan.has_value() && !scan->ranges.empty()) {{\n"
        '      ROS_INFO_ONCE("oa read a scan of %zu ranges", scan->ranges.size());\n    }'), encoding="utf-8")
    build_log = rosrun.build(project)
    data = _data_topics(model)
    topics = [*data, *(f"{t}/verify" for t in data)]
    bag = base / "run.bag"
    record_bag = ["rosbag", "record", "--quiet", "-O", str(bag), *data]
    # a stock subscriber of its own (rospy shares one subscription per topic and process)
    stock = [rosrun.SYSTEM_PYTHON, str(rosrun.RECORDER), str(base / "stock.jsonl"),
             f"/{model.name}/planner/path=nav_msgs/Path"]
    with rosrun.master(project, base / "ros") as env:
        output = rosrun.run_system(env, package_name(model.name), f"{model.name}.launch", RUN_SECONDS,
                                   base / "run.jsonl", topics, base / "latency" / "summary", beside=[record_bag, stock])
        assert "escalating" not in output, output  # every node stopped on SIGINT
    records = rosrun.recorded(base / "run.jsonl")
    stock_records = rosrun.recorded(base / "stock.jsonl")
    summaries = [json.loads(p.read_text()) for p in (base / "latency" / "summary").glob("*.json")]
    summaries = {s["node"]: s for s in summaries}
    return {"model": model, "model_dir": model_dir, "project": project, "records": records,
            "summaries": summaries, "build_log": build_log, "base": base, "bag": bag, "stock": stock_records}


def _by_task(jobs: list[dict], node: str, task: str) -> list[dict]:
    return sorted((j for j in jobs if j["node"] == node and j["task"] == task), key=lambda j: j["seq"])


def _node(model, task_id: str) -> tuple[str, str]:
    instance, task = task_id.split(".")
    return f"/{model.name}/{instance}", task


def test_the_generated_code_compiles_without_warnings(live):
    assert "warning" not in live["build_log"].lower(), live["build_log"]


def test_every_task_ran_and_no_job_was_lost(live):
    jobs = rosrun.jobs(live["records"])
    model = live["model"]
    for task in model.tasks:
        node, name = _node(model, task.id)
        ran = _by_task(jobs, node, name)
        assert len(ran) >= 5, f"{task.id} ran {len(ran)} times"
        assert [j["seq"] for j in ran] == list(range(1, len(ran) + 1)), f"{task.id}: a job record is missing"


def test_a_prescaled_task_runs_on_exactly_every_kth_arrival(live):
    model, jobs = live["model"], rosrun.jobs(live["records"])
    checked = 0
    for task in model.tasks:
        if task.activation.kind != "trigger":
            continue
        k = task.activation.prescaler
        ran = _by_task(jobs, *_node(model, task.id))
        assert all(j["event"] % k == 0 for j in ran), task.id
        gaps = {b["trigger_seq"] - a["trigger_seq"] for a, b in zip(ran, ran[1:])}
        assert gaps == {k}, f"{task.id}: released after {gaps} arrivals, not every {k}"
        checked += k > 1
    assert checked, "the example has a prescaled trigger"


def test_the_triggering_arrivals_are_the_writer_messages(live):
    """The mapper's releases are every 10th scan message the laser published (their records on the wire)."""
    model = live["model"]
    scans = _records(live, f"/{model.name}/laser/scan")
    indices, seqs = [m["index"] for m in scans], [m["seq"] for m in scans]
    assert indices == list(range(1, len(indices) + 1)), "scan records were lost on the wire"
    assert seqs == indices  # (every job of the laser wrote its scan)
    mapper = _by_task(rosrun.jobs(live["records"]), *_node(model, "mapper.CurMapTask"))
    assert {j["trigger_seq"] for j in mapper} <= set(seqs)


def test_records_beside_the_messages_carry_their_jobs_identity_and_stamps(live):
    model, jobs = live["model"], rosrun.jobs(live["records"])
    laser = {j["seq"]: j for j in _by_task(jobs, *_node(model, "laser.LaserTask"))}
    records = _records(live, f"/{model.name}/laser/scan")
    scans = [r for r in live["records"] if r["topic"] == f"/{model.name}/laser/scan"]
    assert records and abs(len(scans) - len(records)) <= 1  # one record per message (the last may be cut off)
    for m in records:
        job = laser[m["seq"]]
        assert (m["release"], m["start"], m["finish"]) == (job["release"], job["start"], job["finish"])
        assert sorted(list(s) for s in m["stamps"]) == sorted(h[:4] for h in job["held"] if h[4] == "scan")


def test_every_topic_carries_its_real_ros_type(live):
    """On the wire each port's topic has the ROS message its type is bound to, as its publisher declares
    it (so rostopic, rviz and stock nodes understand it); the records are beside them, on TOPIC/verify."""
    model = live["model"]
    for topic, kind in _data_topics(model).items():
        declared = {(r["type"], r["publisher"]) for r in live["records"] if r["topic"] == topic and "hex" in r}
        node = topic.rsplit("/", 1)[0]
        assert declared == {(kind, node)}, topic
        records = {(r["type"], r["publisher"]) for r in live["records"] if r["topic"] == f"{topic}/verify"}
        assert records == {("std_msgs/UInt8MultiArray", node)}, topic
    assert {m.ros1 for m in model.messages} == {"sensor_msgs/LaserScan", "geometry_msgs/PoseStamped",
                                                "geometry_msgs/Twist", "nav_msgs/OccupancyGrid", "nav_msgs/Path"}


def test_a_stock_subscriber_receives_the_planned_path_as_its_type(live):
    """rospy's own nav_msgs/Path subscriber, in a process of its own (ROS connects it only if type and
    checksum match): it receives what the planner published."""
    model = live["model"]
    typed = [r for r in live["stock"] if r["topic"] == f"/{model.name}/planner/path"]
    raw = [r for r in live["records"] if r["topic"] == f"/{model.name}/planner/path" and "hex" in r]
    assert len(typed) >= 5 and {r["typed"] for r in typed} == {"nav_msgs/Path"}
    assert abs(len(typed) - len(raw)) <= 1


def _bag_topics(bag: Path) -> dict[str, tuple[str, int]]:
    """Topic -> (type, messages) of a bag, by the rosbag Python API (Debian's python3)."""
    script = ("import json, sys, rosbag\n"
              "info = rosbag.Bag(sys.argv[1]).get_type_and_topic_info().topics\n"
              "print(json.dumps({t: [i.msg_type, i.message_count] for t, i in info.items()}))\n")
    done = subprocess.run([rosrun.SYSTEM_PYTHON, "-c", script, str(bag)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return {t: (kind, n) for t, (kind, n) in json.loads(done.stdout).items()}


def test_rosbag_records_the_real_types(live):
    topics = _bag_topics(live["bag"])
    assert {t: kind for t, (kind, _) in topics.items()} == _data_topics(live["model"])
    assert all(n >= 5 for _, n in topics.values()), topics


def test_timers_run_at_their_rates_within_two_percent(live):
    model, jobs = live["model"], rosrun.jobs(live["records"])
    for task in model.tasks:
        if task.activation.kind != "timer":
            continue
        releases = [j["release"] for j in _by_task(jobs, *_node(model, task.id))]
        mean = Fraction(releases[-1] - releases[0], len(releases) - 1) / 1_000_000_000
        assert abs(mean - task.activation.period) <= task.activation.period / 50, (task.id, float(mean))


def chain_observations(model, jobs: list[dict], index: int) -> dict[str, list[int]]:
    """Data ages and reaction times of chain ``index`` from the job records, by specs/timing.md §4:
    data age f - s per job of the last task holding stamp s; reaction time, per read s_j of the first
    task, f(first job of the last task holding a stamp >= s_j) - s_(j-1)."""
    chain = model.chains[index]
    n = len(chain.tasks)
    first = _by_task(jobs, *_node(model, chain.tasks[0]))
    ends = sorted(_by_task(jobs, *_node(model, chain.tasks[-1])), key=lambda j: j["finish"])
    held = [(j["finish"], h[2], h[3]) for j in ends for h in j["held"] if h[0] == index and h[1] == n - 1]
    starts = [j["start"] for j in first]
    assert {origin for _, origin, _ in held} <= set(starts), "a stamp is not the read of a first-task job"
    assert all(first == starts[0] for _, _, first in held), "a stamp does not carry the first task's first read"
    reactions = []
    for before, read in zip(starts, starts[1:]):
        reached = next((f for f, origin, _ in held if origin >= read), None)
        if reached is not None:
            reactions.append(reached - before)
    return {"data_age": [f - origin for f, origin, _ in held], "reaction_time": reactions}


def test_no_observed_latency_exceeds_the_analysis_bound(live):
    model, jobs = live["model"], rosrun.jobs(live["records"])
    analysis = analyze(model)
    for index, chain in enumerate(analysis.chains):
        seen = chain_observations(model, jobs, index)
        assert seen["data_age"] and seen["reaction_time"], chain.name
        for metric, bound in (("reaction_time", chain.reaction_time.worst), ("data_age", chain.data_age_reduced.worst)):
            worst = Fraction(max(seen[metric]), 1_000_000_000)
            assert worst <= bound, f"chain {chain.name}: observed {metric} {float(worst)} s, bound {float(bound)} s"


def test_verify_trace_reads_the_job_records_and_recomputes_the_monitors_chains(live, capsys):
    """`verify trace` on the run's recording (the /verify/jobs records among the recorder's lines): every
    task paired with its node's records, its jobs counted as recorded, and each chain's data age,
    reaction time and jitter, from what each job's record says it read (specs/trace.md §3), those the
    stamps the nodes carried give, and what the monitors summed up: count, least and greatest, to the ns.
    Each job's execution time is the CPU time its thread spent (its record's `cpu`): what the functional
    code burnt of that clock (BURN_SHARE of the wcet) and the glue's own work, within what the job took
    from start to finish."""
    model, jobs = live["model"], rosrun.jobs(live["records"])
    code = main(["trace", str(live["model_dir"] / MODEL), str(live["base"] / "run.jsonl"), "--format", "json"])
    doc = json.loads(capsys.readouterr().out)
    # (E801 is no failure here: a few jobs of the 150 us and 500 us tasks, a first one among them, used tens
    # to hundreds of us of CPU time more than their code burnt — page faults, interrupts and a virtual
    # machine's stolen time are charged to the running thread — above the 20 % the model leaves)
    assert code in (0, 1) and doc["source"] == "job records" and not doc["unpaired"]["tasks"]
    for task in doc["tasks"]:
        assert task["jobs"] == task["cpu_jobs"] == len(_by_task(jobs, *_node(model, task["task"])))
        assert Fraction(task["execution"]["p50_s"]) <= model.task(task["task"]).wcet, task
    burnt = {t.name: int(t.wcet * BURN_SHARE * 1_000_000_000) for t in model.tasks}
    for job in jobs:  # (what the job burnt of its thread's CPU clock, within what it took)
        assert burnt[job["task"]] <= job["cpu"] <= job["finish"] - job["start"], job
    for index, chain in enumerate(doc["chains"]):
        seen = chain_observations(model, jobs, index)["data_age"]
        monitor = _monitor(live, index)
        assert chain["data_age"]["count"] == len(seen) == monitor["data_age"]["count"], chain["chain"]
        for metric in ("data_age", "reaction_time"):
            measured = [Fraction(chain[metric][f"{q}_s"]) * 10**9 for q in ("min", "max")]
            assert measured == [monitor[metric]["min_ns"], monitor[metric]["max_ns"]], (chain["chain"], metric)
            assert chain[metric]["count"] == monitor[metric]["count"], (chain["chain"], metric)
        assert [Fraction(chain["data_age"][f"{q}_s"]) * 10**9 for q in ("min", "max")] == [min(seen), max(seen)]
        assert Fraction(chain["jitter_s"]) * 10**9 == monitor["jitter"]["value_ns"], chain["chain"]


def test_the_report_shows_the_navigation_examples_measurements_against_its_bounds(live, tmp_path):
    from .test_report import chromium, console_messages

    out = tmp_path / "navigation-measured.html"
    assert main(["report", str(live["model_dir"] / MODEL), "-o", str(out), "--trace",
                 str(live["base"] / "run.jsonl")]) == 0
    section = out.read_text(encoding="utf-8").split('<div id="measured">')[1]
    model = live["model"]
    assert section.count('class="model"') == len(model.tasks)  # every task's [bcet, wcet] with its jobs
    assert section.count('<g class="measured"') == len(model.tasks) + 2 * len(model.chains)
    done = chromium(tmp_path, out, "--dump-dom")
    assert done.returncode == 0 and console_messages(done.stderr) == []


#: a bag of sensor_msgs/LaserScan at 40 Hz, made with the rosbag Python API (Debian's python3)
MAKE_BAG = """\
import sys, rosbag, rospy
from sensor_msgs.msg import LaserScan
with rosbag.Bag(sys.argv[1], "w") as bag:
    for i in range(200):
        at = rospy.Time(1000) + rospy.Duration(0.025 * i)
        scan = LaserScan(angle_min=-1.0, angle_max=1.0, angle_increment=1 / 3, range_min=0.1, range_max=30.0,
                         ranges=[1.0 + i / 100] * 7)
        scan.header.stamp, scan.header.frame_id = at, "laser"
        bag.write("/replay/scan", scan, at)
"""

#: the generated launch with the obstacle avoidance reading the replayed scans instead of the laser's
REPLAY_LAUNCH = """\
<launch>
  <arg name="trace" default="false"/>
  <arg name="summary_dir" default=""/>
  <include file="$(dirname)/Navigation.launch">
    <arg name="trace" value="$(arg trace)"/>
    <arg name="summary_dir" value="$(arg summary_dir)"/>
  </include>
  <param name="/Navigation/oa/topics/scan" value="/replay/scan"/>
  <param name="/Navigation/laser/subscribers/scan" value="1"/>
</launch>
"""


@pytest.fixture(scope="module")
def replayed(live):
    """The built system run with `rosbag play` of a bag of sensor_msgs/LaserScan (made here) on the
    obstacle avoidance's scan topic: messages of a node outside the model."""
    base, project, model = live["base"], live["project"], live["model"]
    bag = base / "scans.bag"
    made = subprocess.run([rosrun.SYSTEM_PYTHON, "-c", MAKE_BAG, str(bag)], capture_output=True, text=True,
                          timeout=120)
    assert made.returncode == 0, made.stderr
    (project / "launch" / "replay.launch").write_text(REPLAY_LAUNCH, encoding="utf-8")
    play = ["rosbag", "play", "--quiet", "--loop", str(bag)]
    with rosrun.master(project, base / "ros-replay") as env:
        output = rosrun.run_system(env, package_name(model.name), "replay.launch", 5, base / "replay.jsonl", [],
                                   base / "summary-replay", beside=[play])
    return {"output": output, "jobs": rosrun.jobs(rosrun.recorded(base / "replay.jsonl"))}


def test_a_replayed_bag_of_laser_scans_drives_the_obstacle_avoidance(replayed):
    """The bag's scans are data without stamps (seq 0: not a job of the model); the obstacle avoidance
    reads them, as the functional code says, and its commands drive the base."""
    assert "oa read a scan of 7 ranges" in replayed["output"], replayed["output"]
    oa = _by_task(replayed["jobs"], "/Navigation/oa", "OATask")
    read = [j["reads"]["scan"] for j in oa if "scan" in j["reads"]]
    assert len(read) >= 20 and set(read) == {0}
    robot = _by_task(replayed["jobs"], "/Navigation/base", "RobotTask")
    assert len(robot) >= 20 and all(j["reads"]["navvel"] > 0 for j in robot)


def _monitor(live, index: int) -> dict:
    model = live["model"]
    node, _ = _node(model, model.chains[index].tasks[-1])
    return live["summaries"][node]["chains"][model.chains[index].name]


def test_the_monitors_agree_with_the_recorded_messages(live):
    model, jobs = live["model"], rosrun.jobs(live["records"])
    for index, chain in enumerate(model.chains):
        seen = chain_observations(model, jobs, index)
        summary = _monitor(live, index)
        ages = seen["data_age"]
        assert summary["data_age"]["count"] == len(ages), chain.name
        assert (summary["data_age"]["min_ns"], summary["data_age"]["max_ns"]) == (min(ages), max(ages))
        assert summary["jitter"]["value_ns"] == max(ages) - min(ages)
        # the monitor keeps one reaction per new origin: the largest of the reactions it stands for
        assert summary["reaction_time"]["max_ns"] == max(seen["reaction_time"]), chain.name
        assert summary["data_age"]["violations"] == summary["reaction_time"]["violations"] == 0


def test_the_nodes_make_a_missing_summary_directory(live):
    """`summary_dir:=…/latency/summary`, neither of which existed: the nodes made it and wrote into it."""
    made = live["base"] / "latency" / "summary"
    assert made.is_dir() and {p.name for p in made.glob("*.json")} == {
        f"{node.lstrip('/').replace('/', '_')}.json" for node in live["summaries"]}
    assert live["summaries"]


def test_a_too_tight_spec_is_reported_by_the_monitor(live):
    """The reactive chain held to 100 ms (it takes about 160 ms): regenerating changes only the
    parameter file, and the monitor reports every violation on /verify/violations."""
    model_dir, project, base = live["model_dir"], live["project"], live["base"]
    before = {p: p.read_bytes() for p in project.rglob("*") if p.is_file() and "build" not in p.parts}
    text = (model_dir / MODEL).read_text(encoding="utf-8")
    (model_dir / MODEL).write_text(text.replace("reaction_time <= 250 ms", "reaction_time <= 100 ms"), encoding="utf-8")
    assert _generate(model_dir, project) == 0
    after = {p: p.read_bytes() for p in project.rglob("*") if p.is_file() and "build" not in p.parts}
    assert {p.relative_to(project).as_posix() for p in after if after[p] != before.get(p)} == {"config/parameters.yaml"}
    model = _model(model_dir)
    with rosrun.master(project, base / "ros-tight") as env:
        rosrun.run_system(env, package_name(model.name), f"{model.name}.launch", 4, base / "tight.jsonl", [],
                          base / "summary-tight")
    records = rosrun.recorded(base / "tight.jsonl")
    violations = [json.loads(str(r["data"])) for r in records if r["topic"] == "/verify/violations"]
    reactive = [v for v in violations if v["chain"] == "reactive" and v["metric"] == "reaction_time"]
    assert reactive and all(v["value_ns"] > v["bound_ns"] == 100_000_000 for v in reactive)
    summary = json.loads((base / "summary-tight" / "Navigation_base.json").read_text())
    assert summary["chains"]["reactive"]["reaction_time"]["violations"] == len(reactive)


# ------------------------------------------------------------------ compounds, a sporadic task, odd names


@pytest.fixture(scope="module")
def tricky(tmp_path_factory):
    """tests/test_gen_ros1.py's system of reserved names, AND/OR compounds, a 30 Hz timer and a sporadic
    task driven from outside (10 Hz on its release topic), built and run for a few seconds."""
    from .test_gen_ros1 import _TRICKY

    rosrun.require_ros()
    base = tmp_path_factory.mktemp("tricky")
    (base / "main.vfy").write_text(_TRICKY, encoding="utf-8")
    project = base / "project"
    assert main(["gen", "ros1", str(base / "main.vfy"), "-o", str(project)]) == 0
    model = verify.load(str(base / "main.vfy")).system(None)
    rosrun.burn_execution_times(project, {t.name: int(t.wcet * BURN_SHARE * 1_000_000_000) for t in model.tasks})
    # the functional code of Kick fails on every second job: the glue logs it and goes on
    sink = project / "user" / "Sink.hpp"
    sink.write_text(sink.read_text(encoding="utf-8").replace(
        "verify_ros1::burn_cpu(80000);",
        "verify_ros1::burn_cpu(80000);\n    static int jobs = 0;\n"
        "    if (++jobs % 2 == 0) {\n      throw std::runtime_error(\"every second kick\");\n    }"), encoding="utf-8")
    build_log = rosrun.build(project)
    kick = ["rostopic", "pub", "-r", "10", "/Tricky/sink/release/Kick", "std_msgs/Empty"]
    with rosrun.master(project, base / "ros") as env:
        output = rosrun.run_system(env, package_name(model.name), "Tricky.launch", 5, base / "run.jsonl", [],
                                   base / "summary", beside=[kick])
        assert "escalating" not in output, output
    return {"model": model, "jobs": rosrun.jobs(rosrun.recorded(base / "run.jsonl")), "build_log": build_log,
            "output": output}


def test_odd_names_compile_without_warnings(tricky):
    assert "warning" not in tricky["build_log"].lower(), tricky["build_log"]


def test_an_and_compound_fires_once_per_fresh_set_of_members(tricky):
    """`both = x & y`, both fed by one writer: an event per write (its second arrival completes the set),
    every 2nd releases; each job reads values newer than the job before it on both members."""
    both = _by_task(tricky["jobs"], "/Tricky/sink", "Both")
    assert len(both) >= 20
    assert {b["trigger_seq"] - a["trigger_seq"] for a, b in zip(both, both[1:])} == {2}
    assert all(b["reads"]["x"] > a["reads"]["x"] and b["reads"]["y"] > a["reads"]["y"] for a, b in zip(both, both[1:]))


def test_an_or_compound_fires_on_every_arrival(tricky):
    anyjobs = _by_task(tricky["jobs"], "/Tricky/sink", "Any")
    writes = _by_task(tricky["jobs"], "/Tricky/n_src", "new")
    events = [j["event"] for j in anyjobs]
    assert events == list(range(events[0], events[0] + len(events)))  # no event without a job
    assert abs(len(anyjobs) - 2 * len(writes)) <= 4  # two arrivals per write (x and y)


def test_cooperative_tasks_of_a_node_never_overlap(tricky):
    jobs = sorted((j for j in tricky["jobs"] if j["node"] == "/Tricky/sink" and j["task"] in ("Both", "Any")),
                  key=lambda j: j["start"])
    assert all(a["finish"] <= b["start"] for a, b in zip(jobs, jobs[1:]))


def test_a_rational_period_is_kept_exactly(tricky):
    releases = [j["release"] for j in _by_task(tricky["jobs"], "/Tricky/n_src", "new")]
    mean = Fraction(releases[-1] - releases[0], len(releases) - 1) / 1_000_000_000
    assert abs(mean - Fraction(1, 30)) <= Fraction(1, 30) / 50


def test_a_sporadic_task_runs_when_released_from_outside(tricky):
    """Kick is released by the messages on its release topic; its functional code throws on every second
    job, which is logged and neither traced nor the end of the node (the other tasks go on)."""
    kicks = _by_task(tricky["jobs"], "/Tricky/sink", "Kick")
    assert len(kicks) >= 8
    events = [j["event"] for j in kicks]
    assert [b - a for a, b in zip(events, events[1:])] == [2] * (len(events) - 1)  # the failed ones: no record
    assert "Kick failed: every second kick; its outputs were not written" in tricky["output"]
    assert _by_task(tricky["jobs"], "/Tricky/sink", "Both")[-1]["finish"] > kicks[-1]["finish"] - 1_000_000_000
