"""`verify import smartmdsd` and `verify export smartmdsd` (specs/interop.md) on the real models in
examples/smartmdsd (from the SmartMDSD toolchain's repositories: origin and licences in its README) and on
small models of every construct."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import verify
from verify.cli import main
from verify.core.diagnostics import DiagnosticSink
from verify.interop.smartmdsd import import_dirs, read_files
from verify.interop.smartmdsd.export import export_system

from .conftest import ROOT

MODELS = ROOT / "examples" / "smartmdsd"
EXAMPLE = ROOT / "examples" / "smartmdsd-gazebo"
GAZEBO = "SystemGazeboP3DXNavigation"


@pytest.fixture(scope="module")
def models() -> Path:
    """The SmartMDSD models the repository ships (examples/smartmdsd)."""
    return MODELS


def imported(paths, system=None):
    sink = DiagnosticSink()
    result, sources = import_dirs([str(p) for p in paths], system, sink)
    return result, sink.items


def signature(model):
    """What a round trip must keep: every task's configuration and every connection and chain (no spans)."""
    tasks = sorted((t.id, t.core, t.priority, t.bcet, t.wcet, t.activation, t.reads, t.produces, t.min_rate,
                    t.max_rate, t.changeable) for t in model.tasks)
    links = sorted((lk.source, lk.target, lk.delay_min, lk.delay_max) for lk in model.links)
    chains = sorted((c.name, c.tasks, c.reaction_time) for c in model.chains)
    return tasks, links, chains


# ------------------------------------------------------------------ the real models


def test_the_gazebo_navigation_system_imports_as_the_example_shows(models):
    result, diagnostics = imported([models], GAZEBO)
    assert result is not None and result.system == GAZEBO
    assert result.text == (EXAMPLE / "imported.vfy").read_text(encoding="utf-8")
    assert not [d for d in diagnostics if d.severity == "error"]
    text = result.text
    assert "task CdlTask priority 0 trigger LaserClient" in text  # DataTriggered Laser { prescale 1 }, via the flow
    assert "reads LaserClient oversampling ok undersampling ok" in text  # InputPortLink flags
    assert "reads PlannerClient optional oversampling ok undersampling ok" in text
    assert "activation 5 Hz .. 40 Hz" in text  # ActivationConstraints, configurable=true
    assert "activation min 10 Hz fixed" in text  # configurable=false
    assert "task BaseStateTask priority 0 timer 20 Hz" in text  # DefaultTrigger PeriodicTimer
    assert "task VelocityInpuHandler priority 0 trigger NavVelServiceIn" in text  # InputHandlerNode
    assert "task CurMapTask priority 0 activation ?" in text  # nothing configures it: a hole for synth
    assert "connect SmartCdlServer.NavVelSendClient -> SmartGazeboBaseServer.NavVelServiceIn" in text
    codes = [d.code for d in diagnostics]
    # the two instances whose components are not in the repository, the three nodes nothing maps
    assert codes.count("E702") == 2 and sum(1 for d in diagnostics if "configures no activity" in d.message) == 3
    # every construct without a counterpart is reported at its own keyword
    sources = {p: Path(p).read_text(encoding="utf-8").split("\n") for p in {d.span.file for d in diagnostics}}
    for d in diagnostics:
        if d.code == "E703" and d.message.startswith("`"):
            word = d.message.split("`")[1]
            line = sources[d.span.file][d.span.line - 1]
            assert line[d.span.column - 1:].startswith(word), d
    laser = next(d for d in diagnostics if d.code == "E704" and "LaserTask" in d.message)
    assert any("maxActFreq" in n for n in laser.notes)


@pytest.mark.parametrize("system", ["SystemGazeboP3DXNavigation", "SystemTiagoNavigation", "SystemGmapping"])
def test_every_shipped_system_imports_without_an_error(models, system):
    result, diagnostics = imported([models], system)
    assert result is not None
    assert not [d for d in diagnostics if d.severity == "error"]
    written = verify.load_text(result.text, "x.vfy")  # the written model parses and its names resolve
    assert not [d for d in written.diagnostics if d.code.startswith(("E0", "E1"))]


def test_several_systems_need_a_choice(models):
    result, diagnostics = imported([models])
    assert result is None and [d.code for d in diagnostics] == ["E705"]


def test_the_completed_example_differs_from_the_import_only_where_it_says(models):
    imported_model = verify.load_text((EXAMPLE / "imported.vfy").read_text(encoding="utf-8"), "i.vfy")
    completed = verify.load(str(EXAMPLE / "completed.vfy"))
    assert completed.ok
    lines = (EXAMPLE / "completed.vfy").read_text(encoding="utf-8").split("\n")
    original = set((EXAMPLE / "imported.vfy").read_text(encoding="utf-8").split("\n"))
    for line in lines:  # every line that is new says it was completed by hand (or is the header)
        if line not in original and line.strip():
            assert "completed" in line or line.strip() in ("}", "reaction_time <= 100 ms") or "chain" in line, line
    assert not [d for d in imported_model.diagnostics if d.code.startswith(("E0", "E1"))]


def test_the_example_round_trips_through_synth_and_export(models, tmp_path):
    """import -> complete -> synth -> export --from -> import gives the synthesized model back, but for what the
    export reports it cannot hold (an input handler's execution times and priority, E707)."""
    out = tmp_path / "synth.vfy"
    assert main(["synth", str(EXAMPLE / "completed.vfy"), "-o", str(out)]) == 0
    model = verify.load(str(out)).system()
    sink = DiagnosticSink()
    origin = read_files([str(models / "systems" / f"{GAZEBO}.componentArch"), str(models / "components")], sink)
    exported = export_system(model, origin.files, {p: s.text for p, s in origin.sources.items()}, sink)
    assert exported is not None
    lost = {d.message.split("`")[1] for d in sink.items if d.code == "E707"}
    assert lost == {"SmartGazeboBaseServer.LocalizationUpdateHandler", "SmartGazeboBaseServer.VelocityInpuHandler"}
    for name, text in exported.files.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    back, diagnostics = imported([tmp_path / f"{GAZEBO}.componentArch", tmp_path / f"{GAZEBO}.activityArch",
                                  tmp_path / f"{GAZEBO}.causeEffectChain", models / "components"])
    assert back is not None
    again = verify.load_text(back.text, "back.vfy")
    assert not again.ok  # the handlers have no wcet: E217, and nothing else
    assert {d.code for d in again.diagnostics if d.severity == "error"} == {"E217"}
    patched = back.text
    for task in ("LocalizationUpdateHandler", "VelocityInpuHandler"):  # as completed.vfy gives them
        patched = patched.replace(f"  task {task} {{\n    reads",
                                  f"  task {task} {{\n    bcet 50 us\n    wcet 100 us\n    reads")
        patched = patched.replace(f"task {task} priority 0", f"task {task} priority 7")
    tasks, links, chains = signature(verify.load_text(patched, "back.vfy").system())
    assert (tasks, links, chains) == signature(model)
    assert len(chains) == 1


def test_the_export_edits_the_component_architecture_minimally(models, tmp_path):
    model = verify.load(str(EXAMPLE / "completed.vfy"))
    out = tmp_path / "synth.vfy"
    assert main(["synth", str(EXAMPLE / "completed.vfy"), "-o", str(out)]) == 0
    dest = tmp_path / "out"
    assert main(["export", "smartmdsd", str(out), "-o", str(dest),
                 "--from", str(models / "systems" / f"{GAZEBO}.componentArch"),
                 "--from", str(models / "components")]) == 0
    original = (models / "systems" / f"{GAZEBO}.componentArch").read_text(encoding="utf-8").split("\n")
    written = (dest / f"{GAZEBO}.componentArch").read_text(encoding="utf-8").split("\n")
    kept = [line for line in written if line in original]
    assert kept == original
    new = [line.strip() for line in written if line not in original]
    assert new and all(line.startswith(("Activity ", "InputHandler ")) and "configuration" in line for line in new)
    assert model.ok
    # a second export does not overwrite
    assert main(["export", "smartmdsd", str(out), "-o", str(dest)]) == 2


# ------------------------------------------------------------------ every construct, small


COMPONENT = """ComponentDefinition Sensor {
	OutputPort Out implements Comm.Scan realizedBy Read { }
	Activity Read {
		ActivationConstraints { configurable=false minActFreq = 40.0 Hz maxActFreq = 40.0 Hz }
	}
}
"""
FILTER = """ComponentDefinition Filter {
	InputPort In implements Comm.Scan { }
	InputPort Aux implements Comm.Scan { }
	OutputPort Out implements Comm.Cmd realizedBy Run { }
	Activity Run {
		InputPortLink In { undersamplingOk }
		InputPortLink Aux { optional oversamplingOk }
		ActivationConstraints { configurable=true minActFreq=5.0 Hz maxActFreq=50.0 Hz }
	}
}
"""
ACTOR = """ComponentDefinition Actor {
	InputPort Cmd implements Comm.Cmd { }
	Activity Act {
		InputPortLink Cmd { oversamplingOk undersamplingOk }
		DefaultTrigger PeriodicTimer 20.0 Hz;
	}
}
"""
SYSTEM = """SystemComponentArchitecture Small usingActivityArchitecture Small {
	ComponentInstance s instantiates Sensor {
		ProvidedService Out
		Activity Read configuration S;
	}
	ComponentInstance s2 instantiates Sensor { ProvidedService Out }
	ComponentInstance f instantiates Filter {
		RequiredService In
		Activity Run configuration F;
	}
	ComponentInstance a instantiates Actor {
		Activity Act configuration A;
	}
	Connection f.In -> s.Out
	Connection f.Aux -> s2.Out
	Connection a.Cmd -> f.Out
}
"""
ACTIVITIES = """ActivityArchitectureModel Small {
	CPUCore CPU0 { coreNumber 0 }
	CPUCore CPU1 { coreNumber 1 }
	ActivityNode S {
		activationSource PeriodicTimer { periodicActFreq 40.0 Hz }
		cpuAffinity CPU0
		executionTime { minTime 200 us maxTime 400 us }
		scheduler { type FIFO priority 9 }
	}
	ActivityNode F {
		inputs { TriggerInputNode scan RegisterInputNode aux }
		activationSource DataTriggered scan { prescale 2 }
		cpuAffinity CPU0
		executionTime { minTime 1 ms maxTime 3 ms }
		scheduler { type FIFO priority 5 }
	}
	ActivityNode A {
		activationSource Sporadic { minActFreq 10.0 Hz maxActFreq 12.5 Hz }
		cpuAffinity CPU1
		executionTime { minTime 500 us maxTime 1 ms }
		scheduler { priority 3 type FIFO }
	}
	DataFlow { source S destination F.scan }
	DataFlow { source F destination A.cmd }
}
"""
CHAINS = """CuaseEffectChainModel Small refinesActivityArch Small {
	ActivityChain loop {
		chainLinks { act.F -> act.A }
		desiredMaxResponse 200 ms
		desiredMinResponse 1 ms
	}
}
"""


def small(tmp_path: Path, **replace: str) -> Path:
    files = {"Sensor.component": COMPONENT, "Filter.component": FILTER, "Actor.component": ACTOR,
             "Small.componentArch": SYSTEM, "Small.activityArch": ACTIVITIES, "Small.causeEffectChain": CHAINS}
    files.update(replace)
    d = tmp_path / "model"
    d.mkdir(exist_ok=True)
    for name, text in files.items():
        (d / name).write_text(text, encoding="utf-8")
    return d


def test_every_mapped_construct(tmp_path):
    result, diagnostics = imported([small(tmp_path)])
    assert result is not None, diagnostics
    text = result.text
    assert "reads In oversampling forbidden undersampling ok" in text
    assert "reads Aux optional oversampling ok undersampling forbidden" in text
    assert "activation 40 Hz fixed" in text and "activation 5 Hz .. 50 Hz" in text
    assert "bcet 1 ms\n    wcet 3 ms" in text
    assert "task Run priority 5 trigger In every 2" in text  # DataTriggered by the flow from S, prescale 2
    assert "instance f : Filter on CPU0" in text and "instance a : Actor on CPU1" in text
    assert "task Act priority 3 sporadic 10 Hz .. 12.5 Hz" in text
    assert "chain loop: f.Out -> a.Act {\n    reaction_time <= 200 ms\n  }" in text
    assert "connect s_.Out -> f.In" in text and "connect f.Out -> a.Cmd" in text
    assert any(d.code == "E703" and "desiredMinResponse" in d.message for d in diagnostics)
    assert "instance s_ : Sensor on CPU0" in text  # `s` is a unit here: renamed (E703)
    assert any(d.code == "E703" and "`s`" in d.message for d in diagnostics)
    # s2 has no node: a fixed rate and no source, so no activation (a hole is only where the rate may change)
    assert "task Read priority 0\n" in text
    model = verify.load_text(text, "small.vfy")
    assert [d.code for d in model.diagnostics if d.severity == "error"] == ["E207"]


def test_a_keyword_as_a_name_is_renamed_and_reported(tmp_path):
    comp = ACTOR.replace("Activity Act", "Activity task").replace("Act configuration", "task configuration")
    system = SYSTEM.replace("Activity Act configuration A;", "Activity task configuration A;")
    result, diagnostics = imported([small(tmp_path, **{"Actor.component": comp, "Small.componentArch": system})])
    assert result is not None and "task task_ " in result.text.replace("{", " ")
    assert any(d.code == "E703" and "`task`" in d.message for d in diagnostics)



@pytest.mark.parametrize("bounds, clause", [("minActFreq=5.0 Hz", "activation min 5 Hz"),
                                            ("maxActFreq=50.0 Hz", "activation max 50 Hz"),
                                            ("minActFreq=0.0 Hz", "activation min 0 Hz")])
def test_one_bound_of_an_activation_constraint_is_imported_as_written(tmp_path, bounds, clause):
    # (a zero minimum once fell through to the missing maximum: an internal error instead of the clause)
    comp = FILTER.replace("minActFreq=5.0 Hz maxActFreq=50.0 Hz", bounds)
    result, diagnostics = imported([small(tmp_path, **{"Filter.component": comp})])
    assert result is not None, diagnostics
    assert f"    {clause}\n" in result.text

def test_a_small_system_round_trips_without_an_origin(tmp_path):
    d = small(tmp_path)
    result, _ = imported([d])
    assert result is not None
    text = result.text.replace("    task Read priority 0\n", "    task Read priority 8 timer 40 Hz\n")
    model = verify.load_text(text, "small.vfy")
    assert model.ok, model.diagnostics
    system = model.system()
    sink = DiagnosticSink()
    exported = export_system(system, None, {}, sink)
    assert exported is not None and not sink.items
    out = tmp_path / "out"
    out.mkdir()
    for name, body in exported.files.items():
        (out / name).write_text(body, encoding="utf-8")
    for name in ("Sensor.component", "Filter.component", "Actor.component"):
        shutil.copy(d / name, out / name)
    back, diagnostics = imported([out])
    assert back is not None, diagnostics
    again = verify.load_text(back.text, "back.vfy")
    assert again.ok, again.diagnostics
    assert signature(again.system()) == signature(system)


@pytest.mark.parametrize("text, marker", [
    ("ActivityArchitectureModel X { ActivityNode N { activationSource PeriodicTimer { periodicActFreq 10.0 } } }",
     "} } }"),
    ("ActivityArchitectureModel X { ActivityNode N { executionTime { minTime 1.5 ms maxTime 2 ms } } }", "1.5"),
    ("ActivityArchitectureModel X { \u0001 }", "\u0001"),
    ("ActivityArchitectureModel X {", None),
])
def test_syntax_errors_are_located(tmp_path, text, marker):
    (tmp_path / "X.activityArch").write_text(text, encoding="utf-8")
    result, diagnostics = imported([tmp_path])
    assert result is None
    d = diagnostics[0]
    where = (1, text.index(marker) + 1 if marker is not None else len(text) + 1)
    assert d.code == "E701" and (d.span.line, d.span.column) == where


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(st.data())
def test_any_damage_to_a_real_model_is_reported_never_raised(tmp_path_factory, data):
    """Cut, duplicate or replace a slice of a real model: the import reports (or imports) and never raises."""
    source = sorted(p for p in MODELS.rglob("*.*") if p.suffix != ".md")  # (the models, not their README)
    path = data.draw(st.sampled_from(source))
    text = path.read_text(encoding="utf-8")
    a = data.draw(st.integers(0, len(text)))
    b = data.draw(st.integers(a, min(len(text), a + 40)))
    junk = data.draw(st.text(alphabet="{}();=.->ActivityNode Hz 1.0\n\"'#/*\u00e9\x00", max_size=12))
    damaged = text[:a] + junk + text[b:]
    d = tmp_path_factory.mktemp("damaged")
    (d / path.name).write_text(damaged, encoding="utf-8")
    for other in source:
        if other.name != path.name:
            shutil.copy(other, d / other.name)
    sink = DiagnosticSink()
    result, _ = import_dirs([str(d)], GAZEBO, sink)
    for diag in sink.items:
        assert diag.span.line >= 1 or diag.span.file == "<command line>"
    if result is not None:
        written = verify.load_text(result.text, "out.vfy")  # what is written parses: names are the files'
        assert not [d for d in written.diagnostics if d.code.startswith("E0")]


# ------------------------------------------------------------------ the command line


def test_the_commands_exit_codes_and_files(models, tmp_path, capsys):
    out = tmp_path / "nav.vfy"
    assert main(["import", "smartmdsd", str(models), "--system", GAZEBO, "-o", str(out)]) == 2  # incomplete
    assert out.read_text(encoding="utf-8") == (EXAMPLE / "imported.vfy").read_text(encoding="utf-8")
    err = capsys.readouterr().err
    assert "written, but incomplete" in err and "E217" in err and "Traceback" not in err
    assert main(["import", "smartmdsd", str(models), "--system", GAZEBO, "-o", str(out)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert main(["import", "smartmdsd", str(models)]) == 2  # three systems: E705, nothing written
    assert "E705" in capsys.readouterr().err
    assert main(["import", "smartmdsd", str(tmp_path / "nowhere")]) == 2
    assert "E004" in capsys.readouterr().err
    assert main(["import", "smartmdsd", str(small(tmp_path))]) == 2  # to standard output (sensors: no wcet)
    assert "system Small {" in capsys.readouterr().out
    assert main(["export", "smartmdsd", str(EXAMPLE / "completed.vfy"), "-o", str(tmp_path / "x")]) == 2
    assert "E218" in capsys.readouterr().err  # holes: synth first
    assert not (tmp_path / "x").exists()
    assert os.path.exists(out)


def test_a_system_with_ros2_executors_is_not_exported(tmp_path, capsys):
    """SmartMDSD's activities are threads; callbacks sharing an executor's thread have no counterpart
    (specs/timing.md §9): E706 at each executor, nothing written."""
    path = ROOT / "examples" / "autoware-reference" / "autoware-single-executor.vfy"
    out = tmp_path / "out"
    assert main(["export", "smartmdsd", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("error[E706]: executor `main` is a ROS 2 executor") == 1
    assert not out.exists() or not any(out.iterdir())
