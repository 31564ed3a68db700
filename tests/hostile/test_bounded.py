"""Hostile input, exhaustion (issue 37): the work of every stage is bounded by the input's size.

Each case is measured by a deterministic count of the work done at a size N and at 4N (characters
scanned, errors recovered from, objects kept), never by wall-clock time; the few large cases run in a
subprocess whose peak memory (``ru_maxrss``) is checked.
"""
from __future__ import annotations

import json
import resource
import subprocess
import sys
import textwrap

import pytest

import verify
from verify.cli import main
from verify.core.diagnostics import DiagnosticSink, Severity
from verify.core.limits import DEFAULT_LIMITS, Limits
from verify.frontend.parse import parse_source
from verify.frontend.recovery import recovery_limit
from verify.outputs.rendering import TEXT_PER_FILE, render_all_text
from verify.core.source import SourceFile

from benchmarks.hostile import generate_trigger_chain

from ..test_prove import E312_SYSTEM

COMPONENT = "component C {\n  out o : T\n  task K {\n    produces o\n    wcet 1 ms\n  }\n}\n"


def _unknown_instances(n: int, padding: str = "") -> str:
    """A system with ``2 n`` errors (E101: two unknown instances on each of ``n`` lines)."""
    lines = [f"  connect nope{i}.o -> nada{i}.i  // {padding}\n" for i in range(n)]
    return COMPONENT + "system S {\n  core c0\n" + "".join(lines) + "}\n"


# ------------------------------------------------------------------ rendering diagnostics


class _CountingText(str):
    """A text that counts the characters its searches scan (what a renderer's look-ups of lines cost)."""

    scanned = 0

    def _count(self, start: int | None, end: int | None) -> None:
        start = 0 if start is None else start if start >= 0 else max(len(self) + start, 0)
        end = len(self) if end is None else min(end, len(self)) if end >= 0 else max(len(self) + end, 0)
        _CountingText.scanned += max(end - start, 0)

    def split(self, sep=None, maxsplit=-1):  # type: ignore[override]
        _CountingText.scanned += len(self)
        return super().split(sep, maxsplit)

    def splitlines(self, keepends=False):  # type: ignore[override]
        _CountingText.scanned += len(self)
        return super().splitlines(keepends)

    def count(self, sub, start=None, end=None):  # type: ignore[override]
        self._count(start, end)
        return super().count(sub, start, end)

    def find(self, sub, start=None, end=None):  # type: ignore[override]
        found = super().find(sub, start, end)
        self._count(start, found + len(sub) if found >= 0 else end)
        return found

    def rfind(self, sub, start=None, end=None):  # type: ignore[override]
        found = super().rfind(sub, start, end)
        self._count(found if found >= 0 else start, end)
        return found


def _rendering_work(n: int, render) -> int:
    text = _unknown_instances(n, "x" * 60)
    result = verify.load_text(text, "big.vfy")
    assert len(result.diagnostics) == 2 * n
    sources = {"big.vfy": SourceFile("big.vfy", _CountingText(text))}
    _CountingText.scanned = 0
    render(result.diagnostics, sources)
    return _CountingText.scanned


@pytest.mark.parametrize("render", [
    pytest.param(lambda ds, sources: render_all_text(ds, sources, per_file=10 ** 9), id="text"),
    pytest.param(lambda ds, sources: verify.outputs.sarif.to_sarif(ds, sources), id="sarif"),
])
def test_rendering_diagnostics_is_linear_in_file_and_diagnostics(render):
    import verify.outputs.sarif  # noqa: F401  (the renderer above)

    small, large = _rendering_work(250, render), _rendering_work(1000, render)
    # (each file 4 times the size with 4 times the diagnostics: linear work is 4 times as much, the
    # file split again per diagnostic 16 times)
    assert small > 0 and large <= 5 * small, (small, large)


def test_a_line_index_is_built_once_per_file(monkeypatch):
    from verify.core import source

    built = []
    real = source.SourceMap.__init__

    def counting_init(self, text):
        built.append(len(text))
        real(self, text)

    monkeypatch.setattr(source.SourceMap, "__init__", counting_init)
    text = _unknown_instances(50)
    result = verify.load_text(text, "big.vfy")
    render_all_text(result.diagnostics, result.sources)
    assert built == [len(text)]


def test_the_text_shows_at_most_the_cap_per_file_and_counts_the_rest():
    n = TEXT_PER_FILE + 25  # (2 n errors)
    result = verify.load_text(_unknown_instances(n), "big.vfy")
    shown = render_all_text(result.diagnostics, result.sources)
    assert shown.count("error[E101]") == TEXT_PER_FILE
    assert f"… and {2 * n - TEXT_PER_FILE} more errors in big.vfy" in shown
    assert shown.endswith(f"\n\n{2 * n} errors")
    # the first ones in the order given are those shown
    assert "unknown instance `nope0`" in shown and f"`nada{n - 1}`" not in shown


def test_the_count_of_the_rest_names_each_severity_and_each_file():
    sink = DiagnosticSink()
    for file, count in (("a.vfy", 4), ("b.vfy", 1)):
        for i in range(count):
            sink.emit("E101", f"unknown instance `x{i}`", verify.core.source.Span(file, i + 1, 1, i + 1, 2))
    sink.emit("E101", "a warning", verify.core.source.Span("a.vfy", 9, 1, 9, 2), severity=Severity.WARNING)
    shown = render_all_text(sink.items, {}, per_file=2)
    assert shown.count("error[E101]") == 3 and "warning[E101]" not in shown
    assert "… and 2 more errors and 1 more warning in a.vfy" in shown
    assert "more" not in shown.split("… and 2 more errors and 1 more warning in a.vfy")[1].replace(
        "\n\n5 errors, 1 warning", "")


def test_check_prints_the_cap_and_json_lists_every_diagnostic(tmp_path, capsys):
    path = tmp_path / "big.vfy"
    path.write_text(_unknown_instances(TEXT_PER_FILE), encoding="utf-8")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("error[E101]") == TEXT_PER_FILE
    assert f"… and {TEXT_PER_FILE} more errors in {path}" in err
    assert main(["check", "--format", "json", str(path)]) == 2
    out = json.loads(capsys.readouterr().out)
    assert len(out["diagnostics"]) == 2 * TEXT_PER_FILE == out["summary"]["errors"]


# ------------------------------------------------------------------ error recovery


def _recoveries(monkeypatch, text: str, limits: Limits = DEFAULT_LIMITS) -> tuple[int, list]:
    """(errors Lark's recovery was called for, the diagnostics) of parsing ``text``."""
    from verify.frontend.grammar import lark_parser

    lark = lark_parser()
    real = lark.parse
    calls = [0]

    def parse(text, on_error=None, **kwargs):
        def counted(err):
            calls[0] += 1
            return on_error(err)
        return real(text, on_error=counted, **kwargs)

    monkeypatch.setattr(lark, "parse", parse)
    parsed = parse_source(text, "junk.vfy", limits)
    return calls[0], list(parsed.diagnostics)


@pytest.mark.parametrize("junk", [
    pytest.param(lambda n: "component C { " + "x " * n, id="words-on-one-line"),
    pytest.param(lambda n: "component C {" + "@" * n, id="characters-on-one-line"),
    pytest.param(lambda n: "component C { task T { " + "} wcet " * n, id="clauses-on-one-line"),
])
def test_error_recovery_stops_at_its_limit_on_one_line(monkeypatch, junk):
    limit = recovery_limit(DEFAULT_LIMITS)
    small, diagnostics = _recoveries(monkeypatch, junk(limit * 2))
    large, _ = _recoveries(monkeypatch, junk(limit * 8))
    assert small == large == limit
    assert diagnostics and all(d.span.line == 1 and d.code in ("E001", "E002") for d in diagnostics)


def test_error_recovery_limit_follows_the_syntax_error_limit(monkeypatch):
    limits = Limits(syntax_errors=3)
    count, diagnostics = _recoveries(monkeypatch, "component C { " + "x " * 1000, limits)
    assert count == recovery_limit(limits) < recovery_limit(DEFAULT_LIMITS)
    count, diagnostics = _recoveries(monkeypatch, "component C {\n" + "x\n" * 1000, limits)
    assert count == len(diagnostics) == 3


def test_a_text_that_is_not_a_model_stops_at_its_first_error(monkeypatch):
    count, diagnostics = _recoveries(monkeypatch, "@" * 10_000 + "\n" + "x y\n" * 1000)
    assert count == 1 and [(d.code, d.span.line, d.span.column) for d in diagnostics] == [("E002", 1, 1)]


def _peak_of_parsing(text_expression: str) -> tuple[int, list[tuple[str, int, int]]]:
    """(peak resident memory in bytes, the diagnostics' codes and positions) of a fresh interpreter
    parsing the text ``text_expression`` evaluates to."""
    script = textwrap.dedent(f"""
        import json, resource
        from verify.frontend.parse import parse_source
        text = {text_expression}
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        parsed = parse_source(text, "junk.vfy")
        after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print(json.dumps([(after - before) * 1024, [(d.code, d.span.line, d.span.column) for d in parsed.diagnostics]]))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True)
    peak, diagnostics = json.loads(out.stdout)
    return peak, [tuple(d) for d in diagnostics]


def test_an_unterminated_comment_after_an_error_takes_memory_linear_in_its_length():
    # (Lark's lexer once matched a block comment as `(.|\n)*?`: some 250 bytes of stack per character)
    peak, diagnostics = _peak_of_parsing("'component C { x /*' + ' ' * (4 << 20)")
    assert diagnostics == [("E001", 1, 15)]  # (the comment's E002 is on the same line: one report)
    assert peak < 64 << 20, peak


def test_a_file_of_empty_lines_after_an_error_needs_no_list_of_its_lines():
    peak, diagnostics = _peak_of_parsing("'component C { x y' + '\\n' * (4 << 20) + 'z'")
    assert diagnostics[0] == ("E001", 1, 15)
    assert peak < 64 << 20, peak


# ------------------------------------------------------------------ analysis


def _lines_run(code, run) -> int:
    """Lines of ``code`` (a function's ``__code__``) executed while ``run()`` runs: a deterministic
    count of the work of one function."""
    count = [0]

    def local(frame, event, arg):
        if event == "line":
            count[0] += 1
        return local

    def call(frame, event, arg):
        return local if frame.f_code is code else None

    sys.settrace(call)
    try:
        run()
    finally:
        sys.settrace(None)
    return count[0]


def _one_core(n: int, same_priority: bool) -> str:
    instances = "".join(f"  instance i{k} : C on c {{ task T priority {1 if same_priority else n - k} timer 1 s }}\n"
                        for k in range(n))
    return "component C {\n  task T {\n    wcet 1 us\n  }\n}\nsystem S {\n  core c\n" + instances + "}\n"


def _retained_by_analysis(text: str) -> int:
    import tracemalloc

    from verify.timing import analyze

    model = verify.load_text(text, "core.vfy").system()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        result = analyze(model)
        kept = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert all(t.response.wcrt is not None for t in result.tasks)
    return kept


@pytest.mark.parametrize("same_priority", [True, False], ids=["one-level", "one-level-each"])
def test_analysis_memory_is_linear_in_the_tasks_of_a_core(same_priority):
    # (every response once held the ids of all its higher-priority tasks: n²/2 names on one core)
    small = _retained_by_analysis(_one_core(300, same_priority))
    large = _retained_by_analysis(_one_core(1200, same_priority))
    assert large <= 5 * small, (small, large)


def test_interferers_are_hp_in_declaration_order_and_equal_the_tuple():
    import random

    from verify.timing.interferers import CoreOrder, Interferers

    rng = random.Random(37)
    for _ in range(200):
        n = rng.randint(1, 40)
        ids = [f"t{k}" for k in range(n)]
        levels = [rng.randint(0, 5) for _ in range(n)]
        order = CoreOrder(ids, levels)
        for k in range(n):
            extra = tuple(f"r{j}" for j in range(rng.randint(0, 2)))
            view = Interferers(order, levels[k], ids[k], extra)
            expected = tuple(ids[j] for j in range(n) if levels[j] <= levels[k] and j != k) + extra
            assert tuple(view) == expected and len(view) == len(expected)
            assert view == expected and expected == view and hash(view) == hash(expected)
            assert view[:3] == expected[:3] and view[1:] == expected[1:] and view[::2] == expected[::2]
            if expected:
                assert view[0] == expected[0] and view[-1] == expected[-1]
            assert (ids[k] in view) is False


def test_interferers_agree_with_the_reference_analysis():
    from verify.timing import analyze, reference
    from verify.timing.fastrta import response_times

    model = verify.load_text(_one_core(40, same_priority=False), "core.vfy").system()
    result = analyze(model)
    events = {t.id: t.events for t in result.tasks}
    estimates = {t.id: t.response.wcrt for t in result.tasks}
    fast, slow = response_times(model, events, estimates), reference.response_times(model, events, estimates)
    assert fast == slow
    assert fast["i5.T"].interferers == ("i0.T", "i1.T", "i2.T", "i3.T", "i4.T")


def test_the_causal_paths_of_a_long_trigger_chain_cost_what_they_find():
    from verify.timing import analyze
    from verify.timing.fastrta import Round

    def walk_lines(n: int) -> int:
        model = verify.load_text(generate_trigger_chain(n), "chain.vfy").system()
        return _lines_run(Round._causal_paths.__code__, lambda: analyze(model))

    small, large = walk_lines(60), walk_lines(240)
    # (one walk per task through all that lies upstream of it was n²/2 steps per CPA round)
    assert large <= 6 * small, (small, large)


# ------------------------------------------------------------------ prove


def test_the_run_of_e312s_note_is_a_scenario_of_the_budget():
    from verify.prove.core import prove

    model = verify.load_text(E312_SYSTEM, "e312.vfy").system()
    result = prove(model, budget=1)
    (d,) = result.diagnostics
    assert d.code == "E312" and "in 12 ms" in d.notes[-1] and result.explored == 1


def test_e312s_note_is_not_simulated_when_the_budget_is_spent(monkeypatch):
    from verify.prove import core
    from verify.prove.exact import Budget

    def no_run(*args, **kwargs):
        raise AssertionError("simulated beyond the budget")

    monkeypatch.setattr(core, "replay", no_run)
    model = verify.load_text(E312_SYSTEM, "e312.vfy").system()
    responses = verify.timing.analyze(model)
    spent = Budget(1)
    assert spent.take()
    (d,) = core.unbounded(model, {t.id: t.response for t in responses.tasks}, spent)
    assert d.notes[-1].endswith("was not simulated: the scenario budget (`--budget`) was spent")
    (d,) = core.unbounded(model, {t.id: t.response for t in responses.tasks}, Budget(5, deadline=0.0))
    assert d.notes[-1].endswith("was not simulated: the timeout (`--timeout`) had passed")


def test_a_simulation_with_a_deadline_stops_within_a_clock_period():
    from verify.prove.scenario import ConcreteScenario, replay
    from verify.prove.sim import CLOCK_EVERY, SimulationTimeout

    model = verify.load_text(E312_SYSTEM, "e312.vfy").system()
    with pytest.raises(SimulationTimeout) as stopped:
        replay(model, ConcreteScenario(verify.timing.Fraction(10 ** 6)), 10 ** 9, deadline=0.0)
    assert stopped.value.at is not None
    assert str(stopped.value).startswith(f"the deadline passed after {CLOCK_EVERY} events")


def test_prove_with_a_small_budget_and_timeout_ends_within_them(tmp_path, capsys):
    # 40 echo loops on one core: the reference run of E312's note takes minutes without a timeout
    loops = "".join(f"  instance e{i} : Echo on cpu {{ task Run priority {i + 1} trigger any }}\n"
                    f"  connect ticker.tick -> e{i}.tick\n  connect e{i}.echo -> e{i}.again\n" for i in range(40))
    text = E312_SYSTEM.split("system Robot")[0].replace("wcet 1 ms", "wcet 1 us") + (
        "system Robot {\n  core cpu\n  instance ticker : Ticker on cpu { task Tick priority 100 timer 1 ms }\n"
        + loops + "}\n")
    path = tmp_path / "loops.vfy"
    path.write_text(text, encoding="utf-8")
    started = resource.getrusage(resource.RUSAGE_SELF).ru_utime
    assert main(["prove", "--budget", "1", "--timeout", "1", str(path)]) == 3
    assert resource.getrusage(resource.RUSAGE_SELF).ru_utime - started < 30  # (CPU seconds: generous)
    err = capsys.readouterr().err
    assert err.count("error[E312]") == 40
    assert "was not simulated: the timeout (`--timeout`) passed while it ran" in err
