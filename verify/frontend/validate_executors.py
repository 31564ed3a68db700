"""Validation of ROS 2 executors and callback groups (specs/timing.md §9, specs/diagnostics.md).

* E219: an executor needs a core and a priority; E309: the priority is a non-negative integer.
* E222: an executor's threads have a priority of their own on each of their cores (no task and no other
  executor of the core shares it).
* E224: the threads fit the kind: ``N threads`` and several cores are for a ``multi_threaded``
  executor, which has a thread on each of its cores (N at least their number) and its cores to itself.
* E223: a callback group fits its callbacks: a ``group`` clause belongs to a task bound to an executor,
  and the callbacks of one group run on one executor (rclcpp adds a group to one executor).
"""
from __future__ import annotations

from collections.abc import Sequence

from ..model import syntax as s
from ..core.diagnostics import DiagnosticSink, Label
from .resolve import SystemScope
from ..model.units import fmt_number

Bound = tuple[s.Instance, s.Task, s.TaskBinding | None]


def check_executors(scope: SystemScope, tasks: Sequence[Bound], sink: DiagnosticSink) -> None:
    """Every check of this module, over the system's executors and its (instance, task, binding)s."""
    threads: dict[tuple[str, int], s.Executor] = {}
    owned: dict[str, s.Executor] = {}  # core -> the multi-threaded executor that owns it
    for ex in scope.system.executors:
        for span in ex.repeated:
            sink.emit("E212", f"this clause is given more than once for executor `{ex.name.text}`", span,
                      "given again here", help="keep one of them")
        if _check_priority(ex, sink) and _check_threads(ex, sink):
            _claim_threads(ex, threads, owned, sink)
    _check_task_threads(tasks, threads, owned, sink)
    _check_groups(tasks, sink)


def _check_priority(ex: s.Executor, sink: DiagnosticSink) -> bool:
    """E219, E309."""
    if ex.core is None or ex.priority is None:
        missing = [what for what, clause in (("core", ex.core), ("priority", ex.priority)) if clause is None]
        sink.emit("E219", f"executor `{ex.name.text}` has no {' and no '.join(missing)}", ex.name.span,
                  "no " + " and no ".join(missing),
                  help=f"write `executor {ex.name.text} {ex.kind.text} on CORE priority N`: its thread runs "
                       "on that core at that priority")
        return False
    if not ex.priority.is_integer or ex.priority.value < 0:
        sink.emit("E309", f"priority of executor `{ex.name.text}` must be a non-negative integer, found "
                  f"{fmt_number(ex.priority.value)}", ex.priority.span, "not a priority",
                  help="use a whole number such as `priority 3`")
        return False
    return True


def _check_threads(ex: s.Executor, sink: DiagnosticSink) -> bool:
    """E224: threads and cores that fit the executor's kind."""
    name, cores = ex.name.text, ex.cores
    if ex.kind.text != "multi_threaded":
        extra = ex.threads.span if ex.threads is not None else (cores[1].span if len(cores) > 1 else None)
        if extra is not None:
            sink.emit("E224", f"executor `{name}` is {ex.kind.text}: it has one thread, on one core", extra,
                      "for a multi-threaded executor",
                      help=f"declare `executor {name} multi_threaded N threads on CORE, …` for several threads, "
                           "or keep one core")
            return False
        return True
    seen: dict[str, s.Name] = {}
    for core in cores:
        if core.text in seen:
            sink.emit("E224", f"executor `{name}` lists core `{core.text}` twice", core.span, "listed again",
                      secondary=(Label(seen[core.text].span, "first listed here"),), help="list each core once")
            return False
        seen[core.text] = core
    if ex.threads is not None and (not ex.threads.is_integer or ex.threads.value < len(cores)):
        sink.emit("E224", f"executor `{name}` has {fmt_number(ex.threads.value)} threads on {len(cores)} "
                  f"core{'s' if len(cores) != 1 else ''}", ex.threads.span, "not a thread for each core",
                  help=f"give it a whole number of threads of at least {len(cores)} (thread k runs on core "
                       "k mod the number of cores), or list fewer cores")
        return False
    return True


def _claim_threads(ex: s.Executor, threads: dict[tuple[str, int], s.Executor], owned: dict[str, s.Executor],
                   sink: DiagnosticSink) -> None:
    """E222 and E224 between executors: a priority of its own on each core; a multi-threaded executor's
    cores its own."""
    assert ex.priority is not None
    priority = int(ex.priority.value)
    for core in ex.cores:
        other = owned.get(core.text)
        if other is None and ex.kind.text == "multi_threaded":
            other = next((e for (c, _p), e in threads.items() if c == core.text), None)
        if other is not None:
            mt = ex if ex.kind.text == "multi_threaded" else other
            sink.emit("E224", f"executors `{other.name.text}` and `{ex.name.text}` share core `{core.text}`, "
                      f"which multi-threaded executor `{mt.name.text}` needs to itself", core.span,
                      "shared with another executor", secondary=(Label(other.span, "the other executor"),),
                      help="give the multi-threaded executor cores of its own (specs/timing.md §9.4)")
            return
        if (key := (core.text, priority)) in threads:
            sink.emit("E222", f"executors `{threads[key].name.text}` and `{ex.name.text}` share priority "
                      f"{priority} on core `{core.text}`", ex.priority.span, "shared with another executor",
                      secondary=(Label(threads[key].span, "the other executor"),),
                      help="give each executor thread of a core its own priority")
            return
    for core in ex.cores:
        threads[(core.text, priority)] = ex
        if ex.kind.text == "multi_threaded":
            owned[core.text] = ex


def _check_task_threads(tasks: Sequence[Bound], threads: dict[tuple[str, int], s.Executor],
                        owned: dict[str, s.Executor], sink: DiagnosticSink) -> None:
    """E222 and E224 between a task with a priority and the executors of its core."""
    if not threads:
        return
    for inst, task, b in tasks:
        core = (b.core or inst.core) if b is not None else None
        if b is None or b.executor is not None or core is None:
            continue
        who = f"`{inst.name.text}.{task.name.text}`"
        mt = owned.get(core.text)
        if mt is not None:
            sink.emit("E224", f"task {who} runs on core `{core.text}`, which multi-threaded executor "
                      f"`{mt.name.text}` needs to itself", core.span, "a core of a multi-threaded executor",
                      secondary=(Label(mt.span, "the executor"),),
                      help="move the task to another core, or bind it to the executor (specs/timing.md §9.4)")
            continue
        if b.priority is None or not b.priority.is_integer:
            continue
        other = threads.get((core.text, int(b.priority.value)))
        if other is not None:
            sink.emit("E222", f"task {who} has the priority of executor `{other.name.text}` on core "
                      f"`{core.text}`", b.priority.span, "shared with an executor's thread",
                      secondary=(Label(other.span, "the executor"),),
                      help="give the task or the executor another priority: a thread's priority on a core is "
                           "its own, so that which of them runs first is defined")


def _check_groups(tasks: Sequence[Bound], sink: DiagnosticSink) -> None:
    """E223: a group clause without an executor; one group's callbacks on two executors."""
    first: dict[tuple[str, str], s.TaskBinding] = {}
    for inst, task, b in tasks:
        if b is None or b.group is None:
            continue
        who = f"`{inst.name.text}.{task.name.text}`"
        if b.executor is None:
            sink.emit("E223", f"task {who} names callback group `{b.group.text}` but no executor",
                      b.group.span, "a group of callbacks",
                      help="bind the task to an executor (`executor NAME`), or remove the group: a task with a "
                           "priority is a thread of its own")
            continue
        key = (inst.name.text, b.group.text)
        other = first.setdefault(key, b)
        if other.executor is not None and other.executor.text != b.executor.text:
            sink.emit("E223", f"callback group `{b.group.text}` of instance `{inst.name.text}` has callbacks on "
                      f"executors `{other.executor.text}` and `{b.executor.text}`", b.executor.span,
                      "another executor", secondary=(Label(other.executor.span, "the group's first executor"),),
                      help="bind every callback of a group to one executor (rclcpp adds a group to one "
                           "executor), or put them in two groups")
