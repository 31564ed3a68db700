"""``verify gen ros2``: a ROS 2 (rclpy) ament_python package that runs a configured system as
specs/timing.md defines it.

The mapping from each model construct to code, and what the generated code guarantees, is
specs/codegen.md (§9 for this target). The layout of the generated package ``PKG``:

    package.xml, setup.py, setup.cfg,      glue: an ament_python package (format 3), console scripts
    resource/PKG, requirements.txt         ``unit`` (one process) and ``run_all``; the wheels it runs on
    config/parameters.yaml                 glue: every period, phase, prescaler, priority, CPU and chain
                                           role (``/SYSTEM/UNIT: ros__parameters:``); the only file a
                                           changed configuration changes
    launch/<system>.launch.py              glue: a Python launch description, one node per process
    PKG/system.py                          glue: the structure: processes, instances, ports, topics, tasks
    PKG/main.py, PKG/run.py                glue: one process; every process here, without launch
    PKG/verify_ros2/*.py                   glue: the runtime (verify/gen/ros2_runtime)
    PKG/glue/<Component>.py                glue: per component, its base class
    PKG/user/<Component>.py                user: the class with the component's functional code

A **process** (a *unit*) is one executor of the model (its callbacks, on one thread), one preemptive
task, or the cooperative tasks of one instance: each is a thread with a priority of its own in the
analysis, and Python's global interpreter lock lets one process run one thread at a time.
"""
from __future__ import annotations

import keyword
import re
from collections.abc import Callable
from importlib import resources

from ..model.activations import DataTriggered, Periodic, SporadicSource
from ..model.processes import process_of, processes, subscriptions
from ..model.system import ComponentModel, ExecutorModel, MessageModel, SystemModel, TaskDecl, TaskModel
from ..core.sanitize import comment, yaml_string
from ..core.source import Span
from .ros1 import chain_roles, human, nanoseconds, os_priorities, package_name
from .tree import File, Tree, stamped

TARGET = "ros2"
HELP = "ROS 2 (rclpy) nodes in an ament_python package, parameters, a launch file and a runner"
GENERATOR = "verify gen ros2"
#: the runtime's modules, as the package holds them: source file (verify/gen/ros2_runtime/verify_ros2) and
#: name (its ``__init__.py`` is ``package_init.py`` here: the runtime is data of verify, not a package of it)
RUNTIME = (("package_init.py", "__init__.py"), *((f, f) for f in ("component.py", "dispatch.py", "monitor.py",
                                                                  "params.py", "run.py", "unit.py", "wire.py")))

#: names a generated Python name must not take (keywords, and the names the glue modules bind); ``_``
#: is appended (``py``)
_PY_RESERVED = frozenset(keyword.kwlist) | frozenset(keyword.softkwlist) | {"self", "Component", "Glue"}


def py(name: str) -> str:
    """``name`` as a Python identifier of the generated code: a reserved one gets a trailing ``_``."""
    return name + "_" if name in _PY_RESERVED else name


def ros2_name(name: str) -> str:
    """``name`` as a token of a ROS 2 graph name: starting with a letter, no repeated underscore."""
    name = re.sub(r"_{2,}", "_", name)
    return name if name[:1].isalpha() else "n" + name


def requirements() -> list[str]:
    """The pinned wheels the generated nodes run on (verify/gen/ros2_runtime/requirements.txt)."""
    text = resources.files("verify.gen").joinpath("ros2_runtime", "requirements.txt").read_text(encoding="utf-8")
    return [line.strip() for line in text.splitlines() if line.strip() and not line.startswith("#")]


# ------------------------------------------------------------------ processes


def unit_of(model: SystemModel, task: TaskModel) -> str:
    """The process running ``task`` (``verify.model.processes``), as the generated code names it."""
    return ros2_name(process_of(task).label)


def units(model: SystemModel) -> dict[str, list[TaskModel]]:
    """Every process and its tasks, in system order."""
    return {ros2_name(process.label): tasks for process, tasks in processes(model).items()}


def _executor(model: SystemModel, tasks: list[TaskModel]) -> ExecutorModel | None:
    name = tasks[0].executor
    return next((e for e in model.executors if e.name == name), None) if name is not None else None


def policy(model: SystemModel, tasks: list[TaskModel]) -> str:
    """How the process orders its jobs (verify_ros2.dispatch): an executor's kind, else fixed priority.
    A multi-threaded executor with one worker runs one callback at a time in the single-threaded order
    (timing §9.4: the snapshot's order, timers first)."""
    executor = _executor(model, tasks)
    if executor is None:
        return "fp"
    return "single_threaded" if executor.kind == "multi_threaded" else executor.kind


# ------------------------------------------------------------------ refusals


def differs(model: SystemModel) -> list[tuple[Span, str, str]]:
    """What rclpy cannot run as the analysis assumes (E604): a multi-threaded executor with more than one
    worker, whose callbacks the analysis runs in parallel while the threads of one Python process hold
    the global interpreter lock one at a time."""
    return [(ex.span, f"executor `{ex.name}` runs callbacks on {len(ex.workers)} cores at once, which the threads "
             "of one rclpy process cannot: Python's global interpreter lock runs one of them at a time",
             "give it one core (`multi_threaded on CORE`: one worker, analysed as such), or split its callbacks "
             "over executors of their own (each becomes a process)")
            for ex in model.executors if ex.multi_threaded and len(ex.workers) > 1]


def uncovered(model: SystemModel) -> list[tuple[Span, str, str]]:
    """What the analysis does not charge (E605): without ``arrival_cost``, the work of the processes that
    take arrivals (their in-ports' values and records, a sporadic task's releases by message), which
    preempts the jobs of their cores (specs/codegen.md §9.5). One warning, on the system."""
    if model.arrival_cost is not None:
        return []
    taking = [ros2_name(p.label) for p, tasks in processes(model).items()
              if subscriptions(model, tasks) or any(isinstance(t.activation, SporadicSource) for t in tasks)]
    if not taking:
        return []
    shown = ", ".join(f"`{name}`" for name in taking[:4]) + (f" and {len(taking) - 4} more" if len(taking) > 4 else "")
    which, whose = (f"processes {shown} take", "their cores") if len(taking) > 1 else (f"process {shown} takes",
                                                                                       "its core")
    return [(model.span, f"system `{model.name}` declares no `arrival_cost`, but its {which} arrivals: rclpy's "
             f"work per message taken preempts the jobs of {whose}, and the response times `analyze` reports for "
             "them do not include it",
             "declare what a process spends per value it takes, e.g. `arrival_cost 3 ms` in the system (the "
             "`ros2-glue` benchmark measures it on the machine, specs/timing.md §6.6)")]


def clashes(model: SystemModel) -> list[tuple[Span, Span, str]]:
    """Names the generated code would make one (E603): components (modules, compared ignoring case),
    the ports of a component (parameters of ``on_TASK``, topics), instances, processes."""
    found = _among("component", [(c.name, c.span) for c in model.components], py, fold=True)
    for comp in model.components:
        found += _among(f"component `{comp.name}`'s port", [(p.name, p.span) for p in comp.ports], py)
        found += _among(f"component `{comp.name}`'s port", [(p.name, p.span) for p in comp.ports], ros2_name)
    found += _among("instance", [(i.name, i.span) for i in model.instances], ros2_name)
    seen: dict[str, tuple[str, Span]] = {}
    for task in model.tasks:
        name = unit_of(model, task)
        key = task.executor or (task.instance if task.kind == "cooperative" else task.id)
        if name in seen and seen[name][0] != key:
            found.append((task.span, seen[name][1], f"the process of `{task.id}` is named `{name}` in the "
                          f"generated code, as the process of `{seen[name][0]}` is"))
        seen.setdefault(name, (key, task.span))
    return found


def _among(kind: str, names: list[tuple[str, Span]], made: Callable[[str], str],
           fold: bool = False) -> list[tuple[Span, Span, str]]:
    seen: dict[str, tuple[str, Span]] = {}
    found = []
    for name, span in names:
        key = made(name).casefold() if fold else made(name)
        if key in seen:
            first, first_span = seen[key]
            found.append((span, first_span, f"{kind} `{name}` becomes `{made(name)}` in the generated code, "
                          f"as {kind} `{first}` does"))
        else:
            seen[key] = (name, span)
    return found


# ------------------------------------------------------------------ the tree


def generate(model: SystemModel) -> Tree:
    """The package of a configured system (no synthesis holes: the command checks that first)."""
    pkg = package_name(model.name)
    messages = {m.name: m for m in model.messages}
    files = [File(f"{pkg}/verify_ros2/{name}", _runtime(source), "glue") for source, name in RUNTIME]
    files += [File("package.xml", _package_xml(model, pkg), "glue"), File("setup.py", _setup_py(model, pkg), "glue"),
              File("setup.cfg", _setup_cfg(pkg), "glue"), File(f"resource/{pkg}", "", "glue"),
              File("requirements.txt", "\n".join(requirements()) + "\n", "glue"),
              File("config/parameters.yaml", _parameters(model), "glue"),
              File(f"launch/{ros2_name(model.name)}.launch.py", _launch(model, pkg), "glue"),
              File(f"{pkg}/__init__.py", f'"""The nodes of system {comment(model.name)} ({GENERATOR})."""\n', "glue"),
              File(f"{pkg}/system.py", _system(model, pkg, messages), "glue"),
              File(f"{pkg}/main.py", _main(), "glue"), File(f"{pkg}/run.py", _run(), "glue"),
              File(f"{pkg}/glue/__init__.py", "", "glue")]
    for comp in model.components:
        files.append(File(f"{pkg}/glue/{py(comp.name)}.py", _glue_class(comp, messages), "glue"))
    files.append(File(f"{pkg}/user/__init__.py", "", "user"))
    for comp in model.components:
        files.append(File(f"{pkg}/user/{py(comp.name)}.py", _skeleton(comp, messages), "user"))
    return Tree(tuple(File(f.path, stamped(f.path, f.text, GENERATOR), "glue") if f.owner == "glue" else f
                      for f in files))


def _runtime(name: str) -> str:
    return resources.files("verify.gen").joinpath("ros2_runtime", "verify_ros2", name).read_text(encoding="utf-8")


def _packages(model: SystemModel) -> list[str]:
    return sorted({m.package for m in model.messages} | {"std_msgs"})


def _package_xml(model: SystemModel, pkg: str) -> str:
    return "\n".join([
        '<package format="3">', f"  <name>{pkg}</name>", "  <version>0.0.0</version>",
        f"  <description>The nodes of system {comment(model.name)}, generated by {GENERATOR}.</description>",
        '  <maintainer email="nobody@example.org">nobody</maintainer>', "  <license>MIT</license>",
        "  <exec_depend>rclpy</exec_depend>", *(f"  <exec_depend>{p}</exec_depend>" for p in _packages(model)),
        "  <export>", "    <build_type>ament_python</build_type>", "  </export>", "</package>", ""])


def _setup_py(model: SystemModel, pkg: str) -> str:
    launch = f"launch/{ros2_name(model.name)}.launch.py"
    return "\n".join([
        "from setuptools import setup", "",
        f"PACKAGE = {pkg!r}", "",
        "setup(",
        "    name=PACKAGE,", '    version="0.0.0",',
        '    packages=[PACKAGE, PACKAGE + ".glue", PACKAGE + ".user", PACKAGE + ".verify_ros2"],',
        "    data_files=[",
        '        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),',
        '        ("share/" + PACKAGE, ["package.xml", "requirements.txt"]),',
        '        ("share/" + PACKAGE + "/config", ["config/parameters.yaml"]),',
        f'        ("share/" + PACKAGE + "/launch", [{launch!r}]),',
        "    ],",
        '    install_requires=["setuptools"],', "    zip_safe=True,",
        f"    description={('The nodes of system ' + model.name + ', generated by ' + GENERATOR)!r},",
        '    license="MIT",',
        '    entry_points={"console_scripts": [',
        '        "unit = " + PACKAGE + ".main:main",',
        '        "run_all = " + PACKAGE + ".run:main",',
        "    ]},", ")", ""])


def _setup_cfg(pkg: str) -> str:
    return f"[develop]\nscript_dir=$base/lib/{pkg}\n[install]\ninstall_scripts=$base/lib/{pkg}\n"


def _main() -> str:
    return "\n".join([
        '"""One process of the system: `python -m PACKAGE.main UNIT --ros-args ...`',
        '(or `ros2 run PACKAGE unit UNIT`)."""',
        "import signal", "import sys", "",
        "# (a stop asked for while rclpy is still being imported is kept, and honoured once it is)",
        "STOPPED: list[int] = []",
        "for _sig in (signal.SIGINT, signal.SIGTERM):",
        "    signal.signal(_sig, lambda sig, _frame: STOPPED.append(sig))", "",
        "from . import system  # noqa: E402",
        "from .verify_ros2.unit import main as run_unit  # noqa: E402", "", "",
        "def main() -> int:", "    return run_unit(system, stopped=STOPPED)", "", "",
        'if __name__ == "__main__":', "    sys.exit(main())", ""])


def _run() -> str:
    return "\n".join([
        '"""Every process of the system, here, without the launch package: `python -m PACKAGE.run --help`."""',
        "import importlib", "import sys", "", "from . import system", "from .verify_ros2 import run as runner", "", "",
        "def main() -> int:", "    return runner.main(importlib.import_module(__package__), system)", "", "",
        'if __name__ == "__main__":', "    sys.exit(main())", ""])


def _launch(model: SystemModel, pkg: str) -> str:
    args = (("monitor", "true", "chain stamps and monitors"),
            ("summary_dir", "", "where each process ending a chain writes its monitors' summary (empty: nowhere)"),
            ("trace_dir", "", "where each process writes its job records (empty: nowhere)"),
            ("realtime", "true", "SCHED_FIFO priorities and CPU affinity"),
            ("duration", "0.0", "seconds to run after the agreed start (0: until stopped)"))
    return "\n".join([
        f'"""Launch system {comment(model.name)}: one node per process, its parameters from config/parameters.yaml."""',
        "import os", "import uuid", "",
        "from ament_index_python.packages import get_package_share_directory",
        "from launch import LaunchDescription", "from launch.actions import DeclareLaunchArgument",
        "from launch.substitutions import LaunchConfiguration", "from launch_ros.actions import Node", "",
        f"from {pkg} import system", "", "",
        "def generate_launch_description():",
        f"    params = os.path.join(get_package_share_directory({pkg!r}), 'config', 'parameters.yaml')",
        "    run = 'r' + uuid.uuid4().hex[:12]  # the processes of this launch start together",
        "    arguments = [",
        *(f"        DeclareLaunchArgument({n!r}, default_value={d!r}, description={h!r})," for n, d, h in args),
        "    ]",
        "    settings = {'verify.run': run, " + ", ".join(f"'verify.{n}': LaunchConfiguration({n!r})"
                                                     for n, _d, _h in args) + "}",
        f"    nodes = [Node(package={pkg!r}, executable='unit', name=unit, namespace=system.NAMESPACE,",
        "                  arguments=[unit], parameters=[params, settings], output='screen')",
        "             for unit in system.UNITS]",
        "    return LaunchDescription(arguments + nodes)", ""])


# ------------------------------------------------------------------ the structure (system.py)


def _topic(model: SystemModel, port: str) -> str:
    inst, name = port.split(".", 1)
    return f"/{ros2_name(model.name)}/{ros2_name(inst)}/{ros2_name(name)}"


def _system(model: SystemModel, pkg: str, messages: dict[str, MessageModel]) -> str:
    procs = units(model)
    hosts: dict[str, set[str]] = {}  # instance -> the processes running its tasks
    for name, tasks in procs.items():
        for t in tasks:
            hosts.setdefault(t.instance, set()).add(name)
    unit_table = {name: {"policy": policy(model, tasks), "tasks": [t.id for t in tasks]}
                  for name, tasks in procs.items()}
    instances = {i.name: (f"{pkg}.user.{py(i.component)}", py(i.component)) for i in model.instances}
    ports: dict[str, dict[str, object]] = {}
    in_ports: dict[str, list[str]] = {}
    for inst in model.instances:
        comp = model.component(inst.component)
        for p in comp.ports:
            port = f"{inst.name}.{p.name}"
            bound = messages.get(p.message_type)
            entry: dict[str, object] = {"type": bound.ros2 if bound is not None else None}
            if p.direction == "out":
                readers = {lk.target.split(".")[0] for lk in model.links_from(port)}
                entry.update(topic=_topic(model, port), source="",
                             readers=sum(len(hosts.get(r, ())) for r in sorted(readers)))
            else:
                link = model.link_into(port)
                entry.update(topic=_topic(model, link.source) if link is not None else "",
                             source=unit_of(model, model.task(link.writer)) if link is not None else "", readers=0)
                in_ports.setdefault(inst.name, []).append(p.name)
            ports[port] = entry
    compounds = {c.id: (c.mode, list(c.members)) for c in model.compounds}
    order = {t.id: i for i, t in enumerate(model.tasks)}
    table = {t.id: {"reads": [r.port for r in t.reads], "produces": list(t.produces), "order": order[t.id],
                    "release_topic": f"/{ros2_name(model.name)}/{ros2_name(t.instance)}/release/{ros2_name(t.name)}"}
             for t in model.tasks}
    return "\n".join([
        f'"""The structure of system {comment(model.name)}: its processes, instances, ports and tasks.',
        "", "The configuration (periods, priorities, prescalers, chains) is in config/parameters.yaml.", '"""', "",
        f"NAMESPACE = {ros2_name(model.name)!r}",
        "#: process -> how it orders its jobs, and its tasks",
        f"UNITS = {unit_table!r}",
        "#: instance -> the module and class of its component (the user's)",
        f"INSTANCES = {instances!r}",
        "#: port -> its ROS 2 type (None: JSON in std_msgs/msg/String), topic, the process writing it (an in-port's",
        "#: source), the processes subscribing it (an out-port's readers)",
        f"PORTS = {ports!r}",
        f"IN_PORTS = {in_ports!r}",
        f"COMPOUNDS = {compounds!r}",
        f"TASKS = {table!r}", ""])


# ------------------------------------------------------------------ components


def _port_doc(comp: ComponentModel, name: str, messages: dict[str, MessageModel]) -> str:
    port = comp.port(name)
    assert port is not None
    bound = messages.get(port.message_type)
    return f"{port.message_type} ({bound.ros2 if bound is not None else 'JSON, bound to no ROS message'})"


def _signature(comp: ComponentModel, task: TaskDecl) -> str:
    return ", ".join(["self", *(py(r.port) for r in task.reads), *(py(p) for p in task.produces)])


def _task_doc(comp: ComponentModel, task: TaskDecl, messages: dict[str, MessageModel]) -> list[str]:
    wcet = human(task.wcet) if task.wcet is not None else "?"
    lines = [f'        """{comment(task.name)} ({task.kind}): execution time {human(task.bcet)} .. {wcet}.', ""]
    lines += [f"        {comment(py(r.port))}: Input of {comment(_port_doc(comp, r.port, messages))}, read at "
              "the job's start" + (" (optional)" if r.optional else "") for r in task.reads]
    lines += [f"        {comment(py(p))}: Output of {comment(_port_doc(comp, p, messages))}, published when this "
              "returns" for p in task.produces]
    return lines + ['        """']


def _glue_class(comp: ComponentModel, messages: dict[str, MessageModel]) -> str:
    name = py(comp.name)
    lines = [f'"""The glue of component {comment(comp.name)}: what each task\'s job is given (specs/codegen.md §9).',
             f'The functional code is the user\'s, in user/{name}.py."""', "",
             "from ..verify_ros2 import Component", "", "",
             f"class {name}(Component):"]
    for t in comp.tasks:
        lines += [f"    def on_{t.name}({_signature(comp, t)}):", *_task_doc(comp, t, messages),
                  f"        raise NotImplementedError({('write on_' + t.name + ' in user/' + name + '.py')!r})", ""]
    if not comp.tasks:
        lines += ["    pass", ""]
    return "\n".join(lines)


def _skeleton(comp: ComponentModel, messages: dict[str, MessageModel]) -> str:
    name = py(comp.name)
    lines = [f'"""Component {comment(comp.name)}: your functional code. `verify gen ros2` wrote this file once and',
             "never overwrites it; the glue it builds on (glue/" + name + ".py) is regenerated. Each on_TASK runs one",
             "job: its inputs are the values read when the job started (`x.has_value()`, `x.value`), its outputs",
             '(`y.value`, a fresh message) are published when it returns."""', "",
             f"from ..glue.{name} import {name} as Glue", "", "",
             f"class {name}(Glue):"]
    for t in comp.tasks:
        lines += [f"    def on_{t.name}({_signature(comp, t)}):", *_task_doc(comp, t, messages), ""]
    if not comp.tasks:
        lines += ["    pass", ""]
    return "\n".join(lines)


# ------------------------------------------------------------------ parameters


def _parameters(model: SystemModel) -> str:
    cpus = {core.name: i for i, core in enumerate(model.cores)}
    prio = os_priorities(model)
    roles = chain_roles(model)
    lines = [f"# The configuration of system {comment(model.name)}: one entry per process (ROS 2 node), read",
             "# at start. Times are exact, in ns (\"N\" or \"N/D\"). Every name is a quoted string."]
    for name, tasks in units(model).items():
        top = max(tasks, key=lambda t: t.priority)
        lines += [f"/{ros2_name(model.name)}/{name}:", "  ros__parameters:", "    unit:",
                  f"      cpu: {cpus[top.core]}  # core {comment(top.core)}",
                  f"      os_priority: {prio[top.priority]}", "    tasks:"]
        for inst in dict.fromkeys(t.instance for t in tasks):
            lines.append(f"      {yaml_string(inst)}:")
            for t in (t for t in tasks if t.instance == inst):
                lines.append(f"        {yaml_string(t.name)}:")
                lines += [f"          {line}" for line in activation(t) + [f"priority: {t.priority}"]]
                lines += _roles(roles.get(t.id, []))
        ends = [c for c in model.chains if c.tasks[-1] in {t.id for t in tasks}]
        specs = [(c, [(k, b) for k, b in (("reaction_time", c.reaction_time), ("data_age", c.data_age),
                                            ("jitter", c.jitter)) if b is not None]) for c in ends]
        if specs:
            lines.append("    monitors:  # the chains that end here; their specs")
            for chain, bounds in specs:
                lines += [f"      {yaml_string(chain.name)}:", "        monitor: true"]
                lines += [f"        {k}_ns: {yaml_string(nanoseconds(b))}" for k, b in bounds]
    return "\n".join(lines) + "\n"


def activation(task: TaskModel) -> list[str]:
    """A task's activation in the parameters: its kind and its numbers."""
    act = task.activation
    if isinstance(act, Periodic):
        lines = ['activation: "timer"', f"period_ns: {yaml_string(nanoseconds(act.period))}  # {human(act.period)}"]
        if act.phase is not None:
            lines.append(f"phase_ns: {yaml_string(nanoseconds(act.phase))}")
        return lines
    if isinstance(act, DataTriggered):
        return ['activation: "trigger"', f"trigger: {yaml_string(act.port)}", f"prescaler: {act.prescaler}"]
    assert isinstance(act, SporadicSource)
    return ['activation: "sporadic"', f"min_ns: {yaml_string(nanoseconds(act.min_interarrival))}",
            f"max_ns: {yaml_string(nanoseconds(act.max_interarrival))}"]


def _roles(roles: list[dict[str, object]]) -> list[str]:
    if not roles:
        return []
    lines = ["          roles:"]
    for role in roles:
        lines += [f"            {yaml_string(str(role['name']))}:", f"              position: {role['position']}"]
        lines += [f"              {k}: {yaml_string(str(role[k]))}" for k in ("from", "to") if role[k]]
    return lines
