"""`trace-read` stage: `verify trace`'s LTTng reader (``verify.trace.lttng.read``) on a trace of n events
recorded here by Debian's LTTng from ``tests/trace/ros2_events.c --fast`` (a talker's and a listener's
callbacks back to back, the talker's message linked to its take: seven `ros2` events a job pair). The
recording is made untimed, once per size, in ``benchmarks/out/trace-v2-N`` (the instance's generator;
v2: with the message links); the row times the reading alone and gives the reading process's CPU time
beside the wall-clock time (on a loaded machine they differ). The goal: 10⁷ events in at most 60 s.
"""
from __future__ import annotations

import resource
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
#: events before the first job (the registrations) and per talker-listener job pair
SETUP_EVENTS, EVENTS_PER_PAIR = 11, 7

MODEL = """\
component Talker {
  out chatter : Message
  task timer_callback_0 {
    produces chatter
    wcet 1 ms
  }
}
component Listener {
  in chatter : Message
  task subscription_callback_0 {
    reads chatter
    wcet 1 ms
  }
}
system S {
  core cpu0
  executor main single_threaded on cpu0 priority 10
  instance talker : Talker {
    task timer_callback_0 executor main timer 1 ms
  }
  instance listener : Listener {
    task subscription_callback_0 executor main trigger chatter
  }
  connect talker.chatter -> listener.chatter
  chain chatter: talker.chatter -> listener.subscription_callback_0
}
"""


def trace_instance(n_events: int, seed: int, **_: object) -> str:
    """The model, headed by the path of a recording of about ``n_events`` events (made if missing)."""
    from . import lttnglive

    target = OUT / f"trace-v2-{n_events}"
    if not (target / "done").exists():
        shutil.rmtree(target, ignore_errors=True)
        OUT.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            program = lttnglive.build(Path(tmp))
            pairs = max(1, -(-(n_events - SETUP_EVENTS) // EVENTS_PER_PAIR))
            lttnglive.record(program, ["--fast", str(pairs)], target / "lttng", blocking=True)
        (target / "done").write_text("", encoding="utf-8")
    return f"// trace: {target / 'lttng'}\n" + MODEL


def register(stage: Callable[..., Callable], error: type[Exception], unavailable: dict[str, str]) -> None:
    from . import lttnglive

    missing = lttnglive.missing_tools()
    if missing:
        unavailable["trace-read"] = f"LTTng tools missing: {', '.join(missing)} (scripts/install-tools)"
        return

    @stage("trace-read", "verify.trace.lttng.read of an LTTng trace of n events (ros2_events --fast, recorded "
           "untimed): the babeltrace2 graph, the callbacks' jobs and the messages' links; cpu_s is the reading "
           "process's CPU time",
           sizes=(1_000_000, 10_000_000), quick_sizes=(10_000,), generator=trace_instance)
    def trace_read(inst) -> dict:
        from verify.trace import lttng

        text, size = inst.text, inst.n_tasks
        path = text.splitlines()[0].removeprefix("// trace: ")
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            recording = lttng.read([path])
        except (lttng.Unreadable, lttng.Unavailable) as err:
            raise error(str(err), {}) from None
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        jobs = sum(len(j) for j in recording.jobs.values())
        links = sum(len(k.delays) for k in recording.links.values())
        pairs = (recording.events - SETUP_EVENTS) // EVENTS_PER_PAIR
        if recording.events < size or recording.partial or jobs != 2 * pairs or links != pairs:
            raise error(f"{recording.events} events, {jobs} jobs, {links} messages linked, partial: "
                        f"{recording.partial}", {"events": recording.events})
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        return {"events": recording.events, "jobs": jobs, "links": links, "cpu_s": round(cpu, 2)}
