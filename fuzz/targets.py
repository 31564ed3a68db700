"""The fuzz targets: one function per pipeline stage, each taking the bytes of one input.

A target raises on a finding — an exception escaping the stage (an internal error: the command line
would exit 70) or a broken invariant (``Finding``) — and returns normally otherwise. They run under
atheris (``fuzz.harness``, coverage-guided) and without it (``tests/test_fuzz.py`` replays the seeds
and every regression input through them), so this module never imports atheris.

| target | what runs on the input | invariants |
|---|---|---|
| ``parse`` | ``parse_source`` | every diagnostic located and in the language's words; a tree round-trips |
| ``validate`` | ``verify.load_text``, its text and JSON renderers | located diagnostics; a valid system has a model |
| ``analyze`` | ``verify.timing.analyze``, its text and JSON reports | every response time at least the WCET |
| ``synth`` | ``synthesize`` and its reports | a configuration found passes the independent re-check |
| ``prove`` | ``prove`` and its text, JSON and SARIF reports | the exit code follows the verdicts (and E312) |
| ``fmt`` | ``format_text`` twice | ``fmt(fmt(x)) == fmt(x)``, and ``fmt(x)`` has the tree and the models of ``x`` |
| ``smartmdsd`` | the SmartMDSD reader and import (``interop.smartmdsd``) | located diagnostics; its output parses |
| ``caret`` | the CARET reader and import (``interop.caret``) | located diagnostics; its output parses |
| ``lsp`` | a fresh language server reading the input (``fuzz.lspstream``) | every request answered, no internal error |

In detail: ``parse`` checks that a tree prints (``fmt``) to text that parses to the same tree;
``validate`` runs resolve, validate, models, chains and rates; ``analyze`` takes every configured
system, both data-age variants; ``synth`` every system with holes (at most ``SMALL`` tasks, a small
solver budget); ``prove`` every configured system (at most ``SMALL`` tasks, budget ``PROVE_BUDGET``,
one process). ``smartmdsd`` takes the input as SmartMDSD files, each after a line ``// file NAME.EXT``
(without one, the kind follows the first keyword), and checks that the model it writes has no syntax
error: names are names, numbers exact. ``caret`` takes the input as one architecture file (YAML) and
checks the same of its import.
"""
from __future__ import annotations

import io
import json
from contextlib import redirect_stderr, redirect_stdout
from collections.abc import Callable

#: systems larger than this are only loaded by the synth and prove targets (a mutant that copies a
#: block many times would spend the run in one input)
SMALL = 12
PROVE_BUDGET = 4
SYNTH_RLIMIT = 300_000
PROVE_RLIMIT = 2_000_000
#: what a user must never see in a message (as tests/test_robustness.py)
FORBIDDEN = ("__ANON", "$END", "Token(", "Tree(", "Traceback", "Fraction(", "NoneType")


class Finding(AssertionError):
    """An invariant a stage broke on the input."""


def _check(condition: bool, what: str) -> None:
    if not condition:
        raise Finding(what)


def _text(data: bytes) -> str:
    """The input as text, as the loader reads a file: strict UTF-8, else undecodable bytes replaced
    (the loader would report E003; the stages after it still get fuzzed text)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("utf-8", errors="replace")


def _located(diagnostics, source: str = "") -> None:
    """Every diagnostic located and in the language's words (``FORBIDDEN``, unless the input itself
    holds the word: a message may quote the user's own text)."""
    forbidden = [w for w in FORBIDDEN if w not in source]
    for d in diagnostics:
        _check(bool(d.code and d.message), f"a diagnostic without code or message: {d}")
        _check(d.span.line >= 1 and d.span.column >= 1, f"{d.code} is not located: {d.span}")
        words = d.message + (d.help or "") + d.primary.message
        bad = [w for w in forbidden if w in words]
        _check(not bad, f"{d.code} shows {bad}: {words!r}")


def _render(diagnostics, sources) -> None:
    from verify.outputs.rendering import diagnostics_json, render_all_text

    render_all_text(list(diagnostics), sources)
    json.dumps(diagnostics_json(list(diagnostics)))


# ------------------------------------------------------------------ the stages


def parse(data: bytes) -> None:
    from verify.frontend.fmt import format_module
    from verify.frontend.parse import parse_source

    text = _text(data)
    parsed = parse_source(text, "fuzz.vfy")
    _located(parsed.diagnostics, text)
    _check((parsed.module is None) == any(d.severity.value == "error" for d in parsed.diagnostics),
           "a tree and a syntax error, or neither")
    if parsed.module is not None:
        try:
            printed = format_module(parsed.module)
        except ValueError:  # a tree no text expresses (documented: fmt reports it)
            return
        again = parse_source(printed, "fuzz.vfy")
        _check(again.module == parsed.module, "the printed tree parses to another tree")


def validate(data: bytes) -> None:
    import verify

    result = verify.load_text(_text(data), "fuzz.vfy")
    _located(result.diagnostics, _text(data))
    _render(result.diagnostics, result.sources)
    if result.ok:
        _check(len(result.models) == len(result.project.systems), "a valid system without a model")


def _models(data: bytes, holes: bool, small: bool = False):
    import verify

    result = verify.load_text(_text(data), "fuzz.vfy")
    for _name, model in sorted(result.models.items()):
        if bool(model.holes) == holes and (not small or len(model.tasks) <= SMALL):
            yield result, model


def analyze(data: bytes) -> None:
    from verify.timing import analyze as run, diagnostics_of
    from verify.timing.report import to_json, to_text

    for result, model in _models(data, holes=False):
        for variant in ("reduced", "non-reduced"):
            analysis = run(model, data_age=variant)
            problems = diagnostics_of(analysis)
            _located(problems, _text(data))
            to_text(analysis)
            json.dumps(to_json(analysis))
            _render(problems, result.sources)
            for task in analysis.tasks:
                _check(task.wcrt is None or task.wcrt >= model.task(task.id).wcet,
                       f"{task.id}: response time below its WCET")


def synth(data: bytes) -> None:
    from verify.synth import TooManyCandidates, synthesize
    from verify.synth.report import to_json, to_text
    from verify.synth.writeback import completed_text, recheck

    for result, model in _models(data, holes=True, small=True):
        try:
            found = synthesize(result, model.name, objective="utilisation", rlimit=SYNTH_RLIMIT)
        except TooManyCandidates:
            continue  # (documented: E403)
        _located(found.diagnostics, _text(data))
        to_text(found)
        json.dumps(to_json(found, "fuzz.vfy"))
        if found.model is not None and found.status == "sat":
            text = completed_text(result, found.system, found.choices)
            problems = recheck(result, found.system, text)[3]
            _check(not problems, f"a synthesized configuration fails the re-check: {problems}")


def prove(data: bytes) -> None:
    from verify.prove import prove as run
    from verify.prove.report import to_json, to_text
    from verify.outputs.sarif import to_sarif

    for _result, model in _models(data, holes=False, small=True):
        proof = run(model, budget=PROVE_BUDGET, rlimit=PROVE_RLIMIT, jobs=1)
        _located(proof.diagnostics, _text(data))
        statuses = {v.status for v in proof.verdicts}
        unbounded = any(d.code == "E312" for d in proof.diagnostics)  # (a task nothing proves bounded)
        expected = 1 if "violated" in statuses else 3 if "undecided" in statuses or unbounded else 0
        _check(proof.exit_code == expected, f"exit code {proof.exit_code} for verdicts {sorted(statuses)}")
        to_text(model, proof)
        json.dumps(to_json(model, proof))
        json.dumps(to_sarif(list(proof.diagnostics)))


def fmt(data: bytes) -> None:
    import verify
    from verify.frontend.fmt import format_text

    text = _text(data)
    once, diagnostics = format_text(text, "fuzz.vfy")
    _located(diagnostics, text)
    if once is None:
        return
    twice, _ = format_text(once, "fuzz.vfy")
    _check(twice == once, "fmt is not idempotent")
    before, after = verify.load_text(text, "fuzz.vfy"), verify.load_text(once, "fuzz.vfy")
    _check(before.project.modules == after.project.modules, "fmt changed the tree")
    _check(before.models == after.models, "fmt changed a model")
    _check([d.code for d in before.diagnostics] == [d.code for d in after.diagnostics], "fmt changed the diagnostics")


#: SmartMDSD files in one input: each after a line ``// file NAME``
SMARTMDSD_FILE = "// file "
_KIND_BY_KEYWORD = {"ComponentDefinition": ".component", "SystemComponentArchitecture": ".componentArch",
                    "CuaseEffectChainModel": ".causeEffectChain"}


def smartmdsd(data: bytes) -> None:
    import verify
    from verify.core.diagnostics import DiagnosticSink
    from verify.interop.smartmdsd.read import KINDS, Files, read_text
    from verify.interop.smartmdsd.to_vfy import import_system

    text = _text(data)
    parts = text.split("\n" + SMARTMDSD_FILE) if SMARTMDSD_FILE in text else [text]
    files, sink = Files(), DiagnosticSink()
    for n, part in enumerate(parts):
        head, _, body = part.removeprefix(SMARTMDSD_FILE).partition("\n") if SMARTMDSD_FILE in text else ("", "", part)
        name = head.strip()
        if not name.endswith(KINDS):
            first = body.split(None, 1)[0] if body.split() else ""
            name = f"f{n}" + _KIND_BY_KEYWORD.get(first, ".activityArch")
        read_text(body, name, files, sink)
    if not sink.has_errors:
        result = import_system(files, None, sink)
        if result is not None:
            written = verify.load_text(result.text, "imported.vfy")
            syntax = [d for d in written.diagnostics if d.code.startswith("E0")]
            _check(not syntax, f"the import wrote text with a syntax error: {syntax[:1]}")
    _located(sink.items, text)
    _render(sink.items, {})


def caret(data: bytes) -> None:
    import verify
    from verify.core.diagnostics import DiagnosticSink
    from verify.interop.caret.read import read
    from verify.interop.caret.to_vfy import import_architecture
    from verify.core.limits import DEFAULT_LIMITS
    from verify.core.source import SourceFile

    text, sink = _text(data), DiagnosticSink()
    architecture = read(text, "architecture.yaml", sink, DEFAULT_LIMITS)
    if architecture is not None and not sink.has_errors:
        imported = import_architecture(architecture, None, sink)
        written = verify.load_text(imported.text, "imported.vfy")
        syntax = [d for d in written.diagnostics if d.code.startswith("E0")]
        _check(not syntax, f"the import wrote text with a syntax error: {syntax[:1]}")
    _located(sink.items, text)
    _render(sink.items, {"architecture.yaml": SourceFile("architecture.yaml", text)})


def lsp(data: bytes) -> None:
    from .lspstream import lsp as serve

    serve(data)


TARGETS: dict[str, Callable[[bytes], None]] = {
    "parse": parse, "validate": validate, "analyze": analyze, "synth": synth, "prove": prove, "fmt": fmt,
    "smartmdsd": smartmdsd, "caret": caret, "lsp": lsp,
}


def run(target: str, data: bytes) -> None:
    """Run ``target`` on ``data`` with its output (there should be none) swallowed."""
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
        TARGETS[target](data)
