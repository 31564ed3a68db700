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
from verify.diagnostics import DiagnosticSink, Severity
from verify.limits import DEFAULT_LIMITS, Limits
from verify.parse import parse_source, recovery_limit
from verify.render import TEXT_PER_FILE, render_all_text
from verify.source import SourceFile

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
    pytest.param(lambda ds, sources: verify.sarif.to_sarif(ds, sources), id="sarif"),
])
def test_rendering_diagnostics_is_linear_in_file_and_diagnostics(render):
    import verify.sarif  # noqa: F401  (the renderer above)

    small, large = _rendering_work(250, render), _rendering_work(1000, render)
    # (each file 4 times the size with 4 times the diagnostics: linear work is 4 times as much, the
    # file split again per diagnostic 16 times)
    assert small > 0 and large <= 5 * small, (small, large)


def test_a_line_index_is_built_once_per_file(monkeypatch):
    from verify import source

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
            sink.emit("E101", f"unknown instance `x{i}`", verify.source.Span(file, i + 1, 1, i + 1, 2))
    sink.emit("E101", "a warning", verify.source.Span("a.vfy", 9, 1, 9, 2), severity=Severity.WARNING)
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
    from verify.larkparse import _parser

    lark = _parser()
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
        from verify.parse import parse_source
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
