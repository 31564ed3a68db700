"""CARET architecture files (specs/interop.md, "CARET"): `verify import caret` and `verify export caret`.

``tests/caret/architecture.yaml`` is written from CARET's format as ``caret_analyze``'s exporter writes it
(a timer node, a node whose subscription stores a message a timer publishes from, a subscriber; one
single-threaded executor; a named path through the three)."""
from __future__ import annotations

import random
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.cli import main
from verify.core.diagnostics import DiagnosticSink
from verify.interop.caret import import_dirs
from verify.timing import analyze

from .conftest import EXAMPLES

ARCH = Path(__file__).parent / "caret" / "architecture.yaml"


def _import(path: Path | str) -> tuple[str, list]:
    sink = DiagnosticSink()
    imported, _ = import_dirs([str(path)], None, sink)
    assert imported is not None, [(d.code, d.message) for d in sink.items]
    return imported.text, sink.items


def _complete(text: str) -> str:
    """The import with what the architecture file lacks: every callback's execution time, a core and
    a priority for every executor, a reaction-time spec on every chain."""
    out = []
    for line in text.splitlines():
        out.append(line)
        if line.startswith("  task ") and "{" in line:
            out.append("    bcet 1 ms")
            out.append("    wcet 2 ms")
    text = "\n".join(out) + "\n"
    text = text.replace("system architecture {", "system architecture {\n  core cpu0")
    executors = [ln for ln in text.splitlines() if ln.startswith("  executor ")]
    for k, line in enumerate(executors):
        text = text.replace(line, line.split("  //")[0] + f" on cpu0 priority {10 + k}")
    return "\n".join(ln + " { reaction_time <= 400 ms }" if ln.startswith("  chain ") else ln
                     for ln in text.splitlines()) + "\n"


def test_a_caret_architecture_is_imported_with_its_executors_passings_and_path():
    text, diagnostics = _import(ARCH)
    assert "task callback_0 executor executor_0 timer 100 ms" in text  # /sensor_node's 100 ms timer
    assert "task callback_1 executor executor_0 trigger topic1" in text  # /filter_node's subscription
    assert "connect filter_node.callback_1_to_callback_0 -> filter_node.callback_0_from_callback_1" in text
    assert ("chain sensor_to_actuator: sensor_node.topic1 -> filter_node.callback_1_to_callback_0 -> "
            "filter_node.topic2 -> actuator_node.callback_0") in text
    codes = [d.code for d in diagnostics]
    assert codes.count("E704") == 4 and codes.count("E703") == 1  # times (3 nodes), the executor's core; groups
    where = {d.code: d.span.line for d in diagnostics}
    assert where["E703"] == 17  # the executor's callback_group_names


def test_the_import_is_incomplete_until_times_and_threads_are_given(tmp_path, capsys):
    out = tmp_path / "imported.vfy"
    assert main(["import", "caret", str(ARCH), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("error[E217]") == 4 and err.count("error[E219]") == 1
    completed = verify.load_text(_complete(out.read_text()), "done.vfy")
    assert completed.ok, [(d.code, d.message) for d in completed.diagnostics]
    analysis = analyze(completed.system())
    bound = analysis.chain("sensor_to_actuator").bound("reaction_time").worst
    assert bound is not None and all(t.wcrt is not None for t in analysis.tasks)


def test_export_from_the_original_changes_only_the_named_paths(tmp_path):
    done = tmp_path / "done.vfy"
    text, _ = _import(ARCH)
    done.write_text(_complete(text).replace("chain sensor_to_actuator:", "chain hot:"))
    assert main(["export", "caret", str(done), "-o", str(tmp_path / "out"), "--from", str(ARCH)]) == 0
    original, written = ARCH.read_text(), (tmp_path / "out" / "architecture.yaml").read_text()
    head = original.index("executors:")
    assert written[written.index("executors:"):] == original[head:]  # every other line kept
    assert written.startswith("named_paths:\n- path_name: hot\n")
    assert written[:written.index("executors:")] == original[:head].replace("sensor_to_actuator", "hot")


def test_an_exported_architecture_imports_back_to_the_same_system(tmp_path):
    """Export without --from writes a whole architecture file; importing it gives the same callbacks,
    activations, executors and connections, and the chain through the same tasks."""
    done = tmp_path / "done.vfy"
    text, _ = _import(ARCH)
    done.write_text(_complete(text))
    first = verify.load(str(done)).system()
    assert main(["export", "caret", str(done), "-o", str(tmp_path / "out")]) == 0
    again, _ = _import(tmp_path / "out" / "architecture.yaml")
    second = verify.load_text(_complete(again), "again.vfy").system()
    assert [(t.id, t.activation.kind, t.executor) for t in first.tasks] == [
        (t.id, t.activation.kind, t.executor) for t in second.tasks]
    assert len(first.links) == len(second.links)
    assert [c.tasks for c in first.chains] == [c.tasks for c in second.chains]


def test_the_autoware_executors_example_goes_to_caret_and_back(tmp_path):
    """The reference system on its four executors (AND fusions, a cyclic sampler, an intersection node
    with two callbacks) exported as a CARET architecture and imported again: 24 nodes, the 25
    callbacks on their executors (and the callbacks that store a fusion's or the planner's other
    inputs), the three chains as named paths through the same nodes."""
    source = EXAMPLES / "autoware-reference" / "autoware-executors.vfy"
    model = verify.load(str(source)).system()
    assert main(["export", "caret", str(source), "-o", str(tmp_path / "out")]) == 0
    text, _ = _import(tmp_path / "out" / "architecture.yaml")
    back = verify.load_text(_complete(text), "back.vfy").system()
    assert len(back.instances) == 24 and len(back.executors) == 4
    ours = {t.id: (t.activation.kind, t.executor) for t in model.tasks}
    theirs = {t.id: (t.activation.kind, t.executor) for t in back.tasks}
    assert {k: v for k, v in theirs.items() if k in ours} == ours
    assert [c.name for c in back.chains] == ["hot_path", "localization", "control"]

    def nodes(chain):
        return list(dict.fromkeys(t.split(".")[0] for t in chain.tasks))

    # (a fusion's second input is stored by a callback of its own, E707: the chain passes it, in the same node)
    assert [nodes(c) for c in back.chains] == [nodes(c) for c in model.chains]
    assert back.chains[0].tasks == model.chains[0].tasks  # the hot path enters its fusion by its first port


def test_a_multi_threaded_executor_comes_back_with_its_callback_groups(tmp_path):
    """The reference system on one multi-threaded executor (specs/timing.md §9.4) through CARET and back:
    the executor is multi-threaded again, and every callback is in a group of the same kind with the
    same members (a default group comes back as a declared mutually exclusive group)."""
    source = EXAMPLES / "autoware-reference" / "autoware-multi-threaded.vfy"
    model = verify.load(str(source)).system()
    assert main(["export", "caret", str(source), "-o", str(tmp_path / "out")]) == 0
    text, diags = _import(tmp_path / "out" / "architecture.yaml")
    assert "E703" not in [d.code for d in diags]
    assert "    group detection mutually_exclusive  // /euclidean_cluster_detector/detection" in text
    back = verify.load_text(_complete(text).replace("core cpu0", "core cpu0\n  core cpu1").replace(
        "multi_threaded on cpu0 priority 10", "multi_threaded on cpu0, cpu1 priority 10"), "back.vfy").system()
    assert [(e.kind, e.workers) for e in back.executors] == [("multi_threaded", ("cpu0", "cpu1"))]

    def members(m):
        return sorted(sorted(t.id for t in m.tasks if t.group == g.id and t.id in ours) + [g.kind]
                      for g in m.groups)

    ours = {t.id for t in model.tasks}
    assert members(back) == members(model)


@pytest.mark.parametrize("text, code, line", [
    ("nodes: [\n", "E701", 2),
    ("named_paths: []\nexecutors: []\n", "E701", 1),
    ("named_paths: []\nexecutors: []\nnodes:\n- callbacks: []\n", "E701", 4),
    ("named_paths: []\nexecutors: []\nnodes:\n- node_name: /a\n  callbacks:\n  - callback_name: /a/c\n"
     "    callback_type: timer_callback\n    period_ns: -5\n    symbol: s\n", "E701", 8),
    ("a: &x [1, 2]\nb: *x\n", "E701", 1),
    ("named_paths: []\nexecutors: []\nnodes:\n- node_name: /a\n  subscribes:\n  - topic_name: /t\n"
     "    callback_name: /a/nothing\n", "E705", 6),
    ("named_paths: []\nexecutors:\n- executor_type: custom_executor\n  executor_name: e\n"
     "  callback_group_names: []\nnodes: []\n", "E703", 3),
])
def test_bad_architecture_files_are_located_diagnostics(tmp_path, text, code, line):
    path = tmp_path / "architecture.yaml"
    path.write_text(text)
    sink = DiagnosticSink()
    import_dirs([str(path)], None, sink)
    found = [d for d in sink.items if d.code == code]
    assert found and found[0].span.line == line, [(d.code, d.span.line, d.message) for d in sink.items]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.randoms(use_true_random=False))
def test_a_damaged_architecture_file_never_crashes_the_import(tmp_path_factory, rnd: random.Random):
    """Lines of the example dropped, repeated or cut: the import reports and exits 0 or 2."""
    lines = ARCH.read_text().splitlines()
    for _ in range(rnd.randint(1, 6)):
        k = rnd.randrange(len(lines))
        action = rnd.randrange(3)
        if action == 0:
            del lines[k]
        elif action == 1:
            lines.insert(k, lines[rnd.randrange(len(lines))])
        else:
            lines[k] = lines[k][: rnd.randrange(len(lines[k]) + 1)]
    path = tmp_path_factory.mktemp("damaged") / "architecture.yaml"
    path.write_text("\n".join(lines) + "\n")
    assert main(["import", "caret", str(path), "-o", str(path.with_suffix(".vfy")), "--force"]) in (0, 2)


def test_a_topic_named_like_a_callback_gets_a_name_of_its_own(tmp_path):
    """A component's tasks and ports share one namespace: `/callback_0` the topic and `/a/callback_0` the
    callback do not become two members `callback_0` (E102)."""
    path = tmp_path / "architecture.yaml"
    path.write_text("named_paths: []\nexecutors: []\nnodes:\n- node_name: /a\n  callbacks:\n"
                    "  - callback_name: /a/callback_0\n    callback_type: subscription_callback\n"
                    "    topic_name: /callback_0\n    symbol: s\n  subscribes:\n  - topic_name: /callback_0\n"
                    "    callback_name: /a/callback_0\n")
    text, _ = _import(path)
    assert "in callback_0_2 : Message" in text and "task callback_0 trigger callback_0_2" in text
    checked = verify.load_text(text, "a.vfy")
    assert "E102" not in {d.code for d in checked.diagnostics}


# ------------------------------------------------------------------ callback identity (construction_order)

ORDERED = Path(__file__).parent / "caret" / "construction-order.yaml"


def test_two_callbacks_of_one_name_are_told_apart_by_their_construction_order():
    """CARET's documented sample has two `timer_callback_0` in one node, the second with
    `construction_order: 1`: two tasks, no duplicate; a reference by name alone is order 0."""
    text, diagnostics = _import(ORDERED)
    assert "  task timer_callback_0 {  // timer_callback_0\n" in text
    assert "  task timer_callback_0_order1 {  // timer_callback_0 (construction_order 1)\n" in text
    assert "task timer_callback_0 executor executor_0 timer 100 ms" in text  # (the group names order 0)
    assert "task timer_callback_0_order1 timer 100 ms" in text
    assert text.count("produces ping") == 1
    codes = [d.code for d in verify.load_text(text, "imported.vfy").diagnostics]
    assert "E102" not in codes and "E203" not in codes and "E217" in codes  # (only what is left to complete)
    unknown = [d for d in diagnostics if d.code == "E702" and "callback group" in d.message]
    assert len(unknown) == 1 and (unknown[0].span.line, unknown[0].span.column) == (15, 5)  # the name itself


def test_the_same_callback_twice_is_reported_and_imported_once(tmp_path):
    twice = ORDERED.read_text(encoding="utf-8").replace("    construction_order: 1\n", "")
    path = tmp_path / "twice.yaml"
    path.write_text(twice, encoding="utf-8")
    text, diagnostics = _import(path)
    assert [d.span.line for d in diagnostics if d.code == "E705"] == [33]
    assert text.count("task timer_callback_0 ") == 2  # (the component's task and its binding, once each)


def test_a_construction_order_that_is_no_number_is_malformed(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(ORDERED.read_text(encoding="utf-8").replace("construction_order: 1", "construction_order: x"),
                    encoding="utf-8")
    sink = DiagnosticSink()
    imported, _ = import_dirs([str(path)], None, sink)
    assert imported is None and [(d.code, d.span.line) for d in sink.items] == [("E701", 37)]
