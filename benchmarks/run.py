"""The benchmark runner: time each stage on generated systems of several sizes.

    python -m benchmarks                                  # every available stage at its own default sizes
    python -m benchmarks --sizes 10,100,1000,10000 --repeat 3 --stages parse+check
    python -m benchmarks --quick                          # every stage at tiny sizes, one repetition (smoke test)
    python -m benchmarks --stages unsat-core --profile    # also a cProfile of the stage at its largest size

For each (stage, size) the runner generates one system (``benchmarks.generate``, untimed), prepares
what the stage needs (untimed: e.g. the loaded model for ``analyze``), then runs the stage ``--repeat``
times for wall time (``time.perf_counter``, garbage collector on, as a user would run it) and as many
times again under ``tracemalloc`` for the peak memory the stage allocates (tracing slows a run down, so
the two are never mixed). It prints a Markdown table (median and min–max of both, and what the stage
found: its ``result`` column) and writes JSON to ``benchmarks/out/results.json`` (or ``--out``).

Stages live in the registry ``STAGES`` (name -> callable taking an :class:`Instance` and the stage's
parameters); register one with ``@stage(...)``. A stage measures real work, never a stand-in, and checks
that the work did what it is measured for (else :class:`BenchmarkError`: an error row, with the time it
took). It may return a dict of result fields (status, evaluations, ...), shown in the ``result`` column.

- ``parse+check``: ``verify.load_text`` on the text (parse, resolve, validate, build the model, chain
  checks). The system must load without a single diagnostic.
- ``parse-verify``, ``parse-lark-transformer``, ``parse-lark-standalone``, ``parse-lark-tree``: one valid text
  into the ``verify.model.syntax`` tree by verify's own parse (the fast path of ``verify/frontend/fastparse.py``),
  by Lark's LALR with
  ``transformer=`` (no parse tree), by the parser of ``python -m lark.tools.standalone`` with the same
  transformer, and by Lark's tree then ``TreeBuilder.transform`` (``benchmarks.parsers``), the collector paused as
  ``verify.load_text`` runs (``--param gc=on``: on). Every run's tree must equal the fast path's, spans
  included (a sample of them). Run them together with ``--interleave``.
- ``analyze``: ``verify.timing.analyze`` on the loaded model.
- ``analyze-pipeline``: ``analyze`` of a trigger pipeline at one priority on one core
  (``generate.generate_pipeline_system``): every task must have a WCRT bound.
- ``prove-bound``: ``verify.load_text`` + ``verify.prove.prove`` *from the text* (parsing included), on
  systems with one chain per five tasks; every verdict must be *proved* (target: 10,000 tasks / 2,000
  chains < 2 s).
- ``prove-exact``: ``prove`` of one chain (``generate.generate_chain_system``; the size is the number of
  tasks of the chain, its hyperperiod holds up to 1,000 jobs per task) whose specs are below the
  analysis' bound, so the exact search must decide them (target: 10 tasks, up to 10,000 jobs, < 2 s).
- ``prove-search``: ``prove`` (``--budget`` 50) of a system whose specs are half their reference bound
  (``tightness`` 1/2), so that many are open after the bound and outside the exact class: the
  falsifying search over their cones. Some verdict must have been decided by the search.
- ``synth-feasibility``: ``verify.synth.driver.synthesize(..., objective="none")`` on systems with holes
  (``hole_share`` 1/5, one chain per five tasks); status must be ``sat`` (target: 1,000 tasks < 2 s).
- ``synth-optimum``: ``synthesize`` with the default objective (utilisation); ``sat`` and proven optimal
  (target: 500 tasks < 10 s).
- ``unsat-core``: ``synthesize`` on ``infeasible=True`` instances with holes; ``unsat`` with an E401
  (target: 500 tasks < 5 s).
- Baselines on the ``synth-feasibility`` / ``synth-optimum`` instances, side by side in the same run:
  ``baseline-brute-force`` (``driver.brute_force``: unpruned enumeration up to an evaluation limit),
  ``baseline-random-search`` (random candidate combinations of the unpruned problem, each analysed by
  ``Problem.evaluate``, up to a limit) and ``baseline-z3-direct`` (the solver loop of ``synthesize`` on
  the problem built with ``prune=False``).

A stage may also give ``setup=`` (called untimed before it is measured, e.g. to build a parser) and
``check=`` (called untimed on what each timed run returned; raises BenchmarkError or returns the result
fields). ``--interleave`` measures size by size, the selected stages one repetition each in turn;
``--param KEY=VALUE`` sets a parameter of every selected stage that has it.

A stage states its generator options (``options=``, e.g. ``{"hole_share": Fraction(1, 5)}``; instances
are cached per size, options and chain count), its own parameters (``params=``, with ``quick_params=``
for ``--quick``), its chain count per task (``chains_per_task=``; ``--chains`` overrides it), its default
sizes (``sizes=``, ``quick_sizes=``; ``--sizes`` overrides them for every stage) and its generator
(``generator=``).
"""
from __future__ import annotations

import argparse
import gc
import json
import math
import os
import platform
import random
import re
import statistics
import sys
import time
import tracemalloc
from collections import Counter
from dataclasses import dataclass, field
from datetime import datetime, UTC
from fractions import Fraction
import functools
from functools import cached_property
from pathlib import Path
from typing import Any
from collections.abc import Callable

import verify

from . import hostile, lsp, ros1, ros2, startup, tightness, trace
from .generate import generate_chain_system, generate_executor_system, generate_pipeline_system, generate_system

DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "results.json"
DEFAULT_SIZES = (10, 100, 1000)
QUICK_SIZES = (10, 30)
SCHEMA = "verify.benchmarks/2"
ONE_PER_FIVE = Fraction(1, 5)  # chains per task of the targets (2,000 for 10,000 tasks; 200 for 1,000)
SPAN_SAMPLE = 1000  # the parse-* stages compare every span, except in tuples of more nodes: about this many of them


class BenchmarkError(Exception):
    """A stage did not do what it is measured for (e.g. the system did not load cleanly, a synthesis
    was not proven optimal). ``result`` holds what it found; the runner adds ``seconds``."""

    def __init__(self, message: str, result: dict | None = None):
        super().__init__(message)
        self.result = dict(result or {})
        self.seconds: float | None = None


@dataclass
class Instance:
    """A generated system and what stages derive from it (derived values are computed once, untimed)."""

    n_tasks: int
    seed: int
    options: dict = field(default_factory=dict)  # keyword arguments of the generator
    chains: int | None = None
    generator: Callable[..., str] = generate_system
    generate_seconds: float = 0.0  # set when the text is generated

    @cached_property
    def text(self) -> str:
        kwargs = dict(self.options)
        if self.chains is not None:
            kwargs["chains"] = self.chains
        start = time.perf_counter()
        text = self.generator(self.n_tasks, self.seed, **kwargs)
        self.generate_seconds = time.perf_counter() - start
        return text

    @property
    def name(self) -> str:
        kind = {generate_chain_system: "chain", generate_pipeline_system: "pipeline",
                generate_executor_system: f"executors-{self.options.get('kind', 'single_threaded')}",
                **HOSTILE_NAMES}.get(self.generator, "waters")
        return f"{kind}-{self.n_tasks}-s{self.seed}.vfy"

    @cached_property
    def loaded(self) -> verify.LoadResult:
        return _load_clean(self)

    @cached_property
    def model(self):
        """The semantic model of the system (``verify.model.system.SystemModel``)."""
        return self.loaded.system()

    @cached_property
    def scope(self):
        """The resolved scope of the system (source spans for synthesis diagnostics), as
        ``synthesize`` takes it from a ``LoadResult``."""
        resolution = self.loaded.resolution
        return resolution.systems.get(self.model.name) if resolution is not None else None

    @cached_property
    def syntax(self):
        """The ``verify.model.syntax.Module`` of the text, straight from verify's fast path
        (``verify/frontend/fastparse.py``): the
        reference of the ``parse-*`` stages. Raises BenchmarkError if the fast path does not accept the text
        (``parse_source`` would then time Lark's error path)."""
        from verify.frontend.fastparse import Unparsable

        from .parsers import VerifyEngine

        try:
            return VerifyEngine.fast_path(self.text, self.name)
        except Unparsable:
            raise BenchmarkError(f"verify's fast path (verify/frontend/fastparse.py) does not accept "
                                 f"{self.name}") from None

    @cached_property
    def syntax_spans(self) -> list:
        """The sampled spans of ``syntax`` (``parsers.sampled_spans``)."""
        from .parsers import sampled_spans

        return sampled_spans(self.syntax, SPAN_SAMPLE)

    @cached_property
    def chain_count(self) -> int:
        return sum(1 for line in self.text.splitlines() if line.lstrip().startswith("chain "))

    @cached_property
    def hyperperiod_jobs(self) -> int | None:
        """Jobs in one hyperperiod, as the chain generator states it in its header."""
        found = re.search(r"hyperperiod (\d+) ms with (\d+) jobs", self.text[:400])
        return int(found.group(2)) if found else None

    @cached_property
    def unpruned_space(self) -> tuple[int, float]:
        """(holes, log10 of the number of candidate combinations) of the problem without pruning."""
        from verify.synth.problem import build_problem

        problem = build_problem(self.model, self.scope, prune=False)
        sizes = [len(c.candidates) for c in problem.choices.values()]
        return len(sizes), sum(math.log10(n) for n in sizes if n)


def _load_clean(inst: Instance) -> verify.LoadResult:
    result = verify.load_text(inst.text, inst.name)
    if result.diagnostics:
        first = result.diagnostics[0]
        raise BenchmarkError(f"{inst.name} has {len(result.diagnostics)} diagnostic(s), first "
                             f"{first.code} at line {first.span.line}: {first.message}")
    return result


# ------------------------------------------------------------------------------ the registry

#: stage name -> the measured callable, ``fn(inst, **params)``
STAGES: dict[str, Callable[..., object]] = {}
#: stage name -> one line saying what it measures
DESCRIPTIONS: dict[str, str] = {}
#: stage name -> attributes of the Instance to compute before timing (untimed preparation)
NEEDS: dict[str, tuple[str, ...]] = {}
#: stage name -> generator options of its instances
OPTIONS: dict[str, dict] = {}
#: stage name -> keyword arguments of the stage callable (``QUICK_PARAMS`` override them for --quick)
PARAMS: dict[str, dict] = {}
QUICK_PARAMS: dict[str, dict] = {}
#: stage name -> default sizes and --quick sizes
SIZES: dict[str, tuple[int, ...]] = {}
QUICK: dict[str, tuple[int, ...]] = {}
#: stage name -> the generator of its instances (``generate_system``, ``generate_chain_system``, ...)
GENERATORS: dict[str, Callable[..., str]] = {}
#: stage name -> chains per task (None: the WATERS default of 30-60 chains)
CHAINS_PER_TASK: dict[str, Fraction | None] = {}
#: stage name -> why it is not available here (import failed)
UNAVAILABLE: dict[str, str] = {}
#: stage name -> called (untimed) before each measurement of the stage, e.g. to build a parser once (cache in it)
SETUPS: dict[str, Callable[[], object]] = {}
#: stage name -> ``check(inst, product)``, called after the timer stops on each timed run with what the stage
#: returned: raises BenchmarkError if the work is wrong, else returns the result fields (a dict) or None
CHECKS: dict[str, Callable[..., dict | None]] = {}


def stage(name: str, description: str, *, needs: tuple[str, ...] = (), options: dict | None = None,
          params: dict | None = None, quick_params: dict | None = None, sizes: tuple[int, ...] = DEFAULT_SIZES,
          quick_sizes: tuple[int, ...] = QUICK_SIZES, generator: Callable[..., str] = generate_system,
          chains_per_task: Fraction | None = None, setup: Callable[[], object] | None = None,
          check: Callable[..., dict | None] | None = None):
    """Register the decorated callable as stage ``name``. ``setup`` runs untimed before the stage is measured;
    ``check`` checks what a timed run returned, untimed (a stage that checks its work itself needs neither)."""

    def register(fn: Callable[..., object]) -> Callable[..., object]:
        STAGES[name] = fn
        DESCRIPTIONS[name] = description
        NEEDS[name] = needs
        OPTIONS[name] = dict(options or {})
        PARAMS[name] = dict(params or {})
        QUICK_PARAMS[name] = {**PARAMS[name], **(quick_params or {})}
        SIZES[name] = tuple(sizes)
        QUICK[name] = tuple(quick_sizes)
        GENERATORS[name] = generator
        CHAINS_PER_TASK[name] = chains_per_task
        if setup is not None:
            SETUPS[name] = setup
        if check is not None:
            CHECKS[name] = check
        return fn

    return register


def instance_key(name: str, size: int, chains: int | None) -> tuple:
    return (GENERATORS[name].__name__, size, chains,
            tuple(sorted((k, str(v)) for k, v in OPTIONS[name].items())))


def chains_for(name: str, size: int, override: int | None) -> int | None:
    """The chain count of stage ``name``'s instance of ``size`` tasks (None: the generator's default)."""
    if GENERATORS[name] is not generate_system:
        return None
    if override is not None:
        return override
    ratio = CHAINS_PER_TASK[name]
    return None if ratio is None else max(1, math.floor(size * ratio))


@stage("parse+check", "verify.load_text: parse, resolve, validate, build the model, check the chains",
       sizes=(10, 100, 1000, 10000))
def parse_and_check(inst: Instance) -> None:
    _load_clean(inst)


def _register_parsers() -> None:
    try:
        import lark  # noqa: F401

        from . import parsers
    except Exception as err:
        for key in ("verify", "lark-transformer", "lark-standalone", "lark-tree"):
            UNAVAILABLE[f"parse-{key}"] = f"benchmarks.parsers is not importable ({type(err).__name__}: {err})"
        return

    engines: dict[str, object] = {}  # built once, untimed (the standalone parser is generated then)

    def engine(key: str):
        if key not in engines:
            built = parsers.ENGINES[key]()
            built.parse(generate_system(4, 0), "<warm-up>")  # (Lark compiles its lexers' regexes at first use)
            engines[key] = built
        return engines[key]

    def check(inst: Instance, module) -> dict:
        reference = inst.syntax
        if module != reference:
            raise BenchmarkError(f"the tree differs from parse-verify's: {parsers.first_difference(module, reference)}",
                                 {"tree": "different"})
        spans = parsers.sampled_spans(module, SPAN_SAMPLE)
        if spans != inst.syntax_spans:
            bad = next((i for i, (a, b) in enumerate(zip(spans, inst.syntax_spans)) if a != b), None)
            where = (f"first {spans[bad]!r} for {inst.syntax_spans[bad]!r}" if bad is not None
                     else f"{len(spans)} spans for {len(inst.syntax_spans)}")
            raise BenchmarkError(f"the same tree, other spans: {where}", {"tree": "equal", "spans": "different"})
        return {"tree": "equal", "spans equal": len(spans)}

    descriptions = {
        "verify": "verify.frontend.parse.parse_source on valid input: the fast path of verify/frontend/fastparse.py "
                  "(Lark's table, "
                  "its own lexer, TreeBuilder's callbacks at each reduction)",
        "lark-transformer": "Lark LALR, contextual lexer, transformer= (no parse tree): TreeBuilder's callbacks "
                            "through an adapter (keep_all_tokens, positions from the children)",
        "lark-standalone": "the parser of python -m lark.tools.standalone (generated into benchmarks/out/ at "
                           "benchmark time) with the same transformer",
        "lark-tree": "Lark's parse tree with positions, then TreeBuilder.transform (verify's error path; a "
                     "reference)",
    }

    def register(key: str) -> None:
        @stage(f"parse-{key}", descriptions[key], needs=("syntax", "syntax_spans"), sizes=(10, 100, 1000, 10000),
               params={"gc": "paused"}, setup=lambda: engine(key), check=check)
        def parse_stage(inst: Instance, **params):
            # "paused": the cyclic collector off during the parse, as verify.load_text runs it (verify.core.gcpause;
            # not paused_gc itself, whose exit may run a full collection); "on": as the runner's other stages
            mode = params["gc"]
            if mode == "on":
                return engine(key).parse(inst.text, inst.name)
            if mode != "paused":
                raise BenchmarkError(f"parameter gc is 'paused' or 'on', not {mode!r}")
            enabled = gc.isenabled()
            gc.disable()
            try:
                return engine(key).parse(inst.text, inst.name)
            finally:
                if enabled:
                    gc.enable()

    for key in parsers.ENGINES:
        register(key)


def _register_analyze() -> None:
    try:
        from verify.timing import analyze
    except Exception as err:  # not implemented yet, or broken: say so, measure the rest
        UNAVAILABLE["analyze"] = f"verify.timing.analyze is not importable ({type(err).__name__}: {err})"
        return

    @stage("analyze", "verify.timing.analyze on the loaded model: rates, response times, chain latencies",
           needs=("model",))
    def analyze_stage(inst: Instance) -> None:
        analyze(inst.model)

    @stage("analyze-pipeline", "verify.timing.analyze on a trigger pipeline at one priority on one core (the "
           "worst case of the causal caps: n²/2 of them, many CPA rounds)", needs=("model",), sizes=(100, 300),
           quick_sizes=(10,), generator=generate_pipeline_system)
    def analyze_pipeline(inst: Instance) -> dict:
        result = analyze(inst.model)
        found = {"CPA rounds": result.rounds, "WCRT of the last task": _ms(result.tasks[-1].response.wcrt),
                 "reaction time": _ms(result.chains[0].reaction_time.worst)}
        return _every_wcrt_bounded(result, found, "task")

    for kind in ("single_threaded", "multi_threaded"):
        stage(f"analyze-{kind.replace('_', '-')}", f"verify.timing.analyze on callbacks of {kind} ROS 2 executors, "
              "100 callbacks each (specs/timing.md §9)", needs=("model",), sizes=(1000,), quick_sizes=(100,),
              generator=generate_executor_system, options={"kind": kind})(
                  functools.partial(_analyze_to_largest_wcrt, noun="callback"))


#: the generators of the hostile stages (``benchmarks/hostile.py``) and the names of their instances
HOSTILE_NAMES: dict[Callable[..., str], str] = {
    hostile.generate_unknown_instances: "unknown-instances", hostile.generate_junk_line: "junk-line",
    hostile.generate_one_core: "one-core", hostile.generate_trigger_chain: "trigger-chain"}


def _register_hostile() -> None:
    """Issue 37's big cases: work linear in their size (``benchmarks/hostile.py``)."""
    from verify.outputs.rendering import TEXT_PER_FILE

    @stage("hostile-diagnostics", "verify.load_text and the text rendering of its diagnostics (as `verify check` "
           "shows them) for a file of n lines with two unknown instances each", sizes=(4000, 16000),
           quick_sizes=(100,), generator=hostile.generate_unknown_instances)
    def diagnostics_stage(inst: Instance) -> dict:
        found, lines = hostile.render_diagnostics(inst.text)
        if found != 2 * inst.n_tasks or lines > 10 * TEXT_PER_FILE:
            raise BenchmarkError(f"{found} diagnostics, {lines} lines shown", {"diagnostics": found})
        return {"diagnostics": found, "lines shown": lines}

    @stage("hostile-recovery", "verify.frontend.parse.parse_source on a component opened and then n words on its one "
           "line: error recovery up to its limit", sizes=(100000, 1000000), quick_sizes=(1000,),
           generator=hostile.generate_junk_line)
    def recovery_stage(inst: Instance) -> dict:
        errors = hostile.recover(inst.text)
        if not errors:
            raise BenchmarkError("no syntax error reported")
        return {"syntax errors": errors}

    analyze_bounded = functools.partial(_analyze_to_largest_wcrt, noun="task")
    stage("analyze-one-core", "verify.timing.analyze on n timer tasks on one core at one priority (memory linear "
          "in the tasks of a core)", needs=("model",), sizes=(1000, 10000), quick_sizes=(100,),
          generator=hostile.generate_one_core)(analyze_bounded)
    stage("analyze-trigger-chain", "verify.timing.analyze on an n-hop chain over 8 cores, each task triggered by "
          "the one before, at falling priorities", needs=("model",), sizes=(250, 500, 1000), quick_sizes=(20,),
          generator=hostile.generate_trigger_chain)(analyze_bounded)


def _analyze_to_largest_wcrt(inst: Instance, noun: str) -> dict:
    """``verify.timing.analyze`` on the instance: its CPA rounds and largest WCRT, every one bounded."""
    from verify.timing import analyze

    result = analyze(inst.model)
    found = {"CPA rounds": result.rounds, "largest WCRT": _ms(max(t.response.wcrt or Fraction(0)
                                                                  for t in result.tasks))}
    return _every_wcrt_bounded(result, found, noun)


def _every_wcrt_bounded(result: Any, found: dict, noun: str) -> dict:
    """``found``, or a ``BenchmarkError`` holding it when the analysis did not converge or left a ``noun``
    without a WCRT bound."""
    unbounded = [t.id for t in result.tasks if t.response.wcrt is None]
    if not result.converged or unbounded:
        raise BenchmarkError(f"{len(unbounded)} {noun}(s) without a WCRT bound (converged: {result.converged})",
                             found)
    return found


def _ms(seconds: Fraction | None) -> str:
    if seconds is None:
        return "–"
    from verify.model.units import fmt_time

    return fmt_time(seconds)


def _register_prove() -> None:
    try:
        from verify.prove.core import prove
    except Exception as err:
        for name in ("prove-bound", "prove-exact"):
            UNAVAILABLE[name] = f"verify.prove.core.prove is not importable ({type(err).__name__}: {err})"
        return

    @stage("prove-bound", "verify.load_text + verify.prove.prove from the text (parsing included); every "
           "verdict proved", sizes=(100, 1000, 10000), chains_per_task=ONE_PER_FIVE)
    def prove_bound(inst: Instance) -> dict:
        proof = prove(_load_clean(inst).system())
        statuses = Counter(v.status for v in proof.verdicts)
        by_bound = sum(1 for v in proof.verdicts if v.status == "proved" and v.method == "bound")
        result = {"verdicts": len(proof.verdicts), "proved": statuses["proved"], "by bound": by_bound}
        if statuses["proved"] != len(proof.verdicts):
            bad = next(v for v in proof.verdicts if v.status != "proved")
            raise BenchmarkError(f"{len(proof.verdicts) - statuses['proved']} verdict(s) not proved, first "
                                 f"{bad.name} {bad.kind}: {bad.status} by {bad.method}", result)
        return result

    @stage("prove-exact", "verify.prove.prove of one chain (size = its tasks) whose specs the bound cannot "
           "prove: the exact search over the hyperperiod decides", needs=("model", "hyperperiod_jobs"),
           sizes=(10,), quick_sizes=(4,), generator=generate_chain_system)
    def prove_exact(inst: Instance) -> dict:
        proof = prove(inst.model)
        chain = [v for v in proof.verdicts if v.subject == "chain"]
        result = {"jobs/hyperperiod": inst.hyperperiod_jobs, "scenarios": proof.explored}
        for v in chain:
            result[v.kind] = (f"{v.status} by {v.method} (exact {_ms(v.exact)}, spec {_ms(v.spec)}, "
                              f"bound {_ms(v.bound)})")
        if not chain:
            raise BenchmarkError("the chain has no spec", result)
        undecided = [v for v in proof.verdicts if v.status == "undecided"]
        if undecided:
            raise BenchmarkError(f"{len(undecided)} verdict(s) undecided, first {undecided[0].name} "
                                 f"{undecided[0].kind}: {undecided[0].note}", result)
        inexact = [v for v in chain if not v.method.startswith("exact")]
        if inexact:
            raise BenchmarkError(f"chain {inexact[0].kind} was decided by {inexact[0].method}, not by the exact "
                                 "search", result)
        return result


    @stage("prove-search", "verify.prove.prove of a system whose specs are half their reference bound: the "
           "bound leaves many open, outside the exact class, so the falsifying search runs on their cones",
           needs=("model",), options={"tightness": Fraction(1, 2)}, params={"budget": 50},
           quick_params={"budget": 4}, sizes=(100, 1000), quick_sizes=(30,), chains_per_task=ONE_PER_FIVE)
    def prove_search(inst: Instance, budget: int) -> dict:
        proof = prove(inst.model, budget=budget)
        statuses = Counter(v.status for v in proof.verdicts)
        searched = [v for v in proof.verdicts if v.method == "search"]
        result = {"verdicts": len(proof.verdicts), "by search": len(searched), "violated": statuses["violated"],
                  "undecided": statuses["undecided"], "scenarios": proof.explored}
        if not searched:
            raise BenchmarkError("the bound or an exact method decided everything: no search ran", result)
        return result


def _synth_result(r) -> dict:
    stats = r.stats or {}
    out = {"status": r.status}
    if r.status == "sat" and r.goals:
        out["optimal"] = "yes" if r.optimal else "no"
    if r.values and r.goals:  # also the best configuration found by an undecided run
        out.update({g.name if r.status == "sat" else f"best found {g.name}": _objective_text(g, v)
                    for g, v in zip(r.goals, r.values)})
    out["holes"] = len(r.problem.choices) if r.problem is not None else "–"
    for key, label in (("solver_calls", "solver calls"), ("analyses", "analyses"), ("rlimit_used", "rlimit")):
        if key in stats:
            out[label] = stats[key]
    if r.status == "unsat" and r.explanation is not None:
        out["core"] = f"{len(r.explanation.core)} statement(s)" + (
            ", minimal" if r.explanation.minimal else f" (explanation {r.explanation.status}, not minimal)")
    if r.status != "sat" and r.reason:
        out["reason"] = r.reason
    return out


def _objective_text(goal, value) -> str:
    if value is None:
        return "unbounded"
    if goal.kind == "utilisation":
        return f"{float(value):.4f}"
    return _ms(value)


def _register_synth() -> None:
    try:
        import z3

        from verify.synth.driver import (DEFAULT_RLIMIT, brute_force, goal_value, objectives_for, parse_objective,
                                         synthesize)
        from verify.synth.problem import Config, build_problem
        from verify.synth.solve import Budget, Engine
    except Exception as err:
        for name in ("synth-feasibility", "synth-optimum", "unsat-core", "baseline-brute-force",
                     "baseline-random-search", "baseline-z3-direct"):
            UNAVAILABLE[name] = f"verify.synth is not importable ({type(err).__name__}: {err})"
        return

    holes = {"hole_share": Fraction(1, 5)}
    synth_sizes = (100, 500, 1000)

    @stage("synth-feasibility", "synthesize(objective=\"none\"): any hole assignment meeting every spec; sat",
           needs=("loaded",), options=holes, sizes=synth_sizes, chains_per_task=ONE_PER_FIVE)
    def synth_feasibility(inst: Instance) -> dict:
        r = synthesize(inst.loaded, objective="none")
        result = _synth_result(r)
        if r.status != "sat":
            raise BenchmarkError(f"status {r.status}: {r.reason}", result)
        return result

    @stage("synth-optimum", "synthesize (objective utilisation): a proven optimal assignment; sat and optimal",
           needs=("loaded",), options=holes, sizes=synth_sizes, chains_per_task=ONE_PER_FIVE)
    def synth_optimum(inst: Instance) -> dict:
        r = synthesize(inst.loaded)
        result = _synth_result(r)
        if r.status != "sat" or not r.optimal:
            raise BenchmarkError(f"not proven optimal: status {r.status}"
                                 + (f" ({r.reason})" if r.reason else ", optimum not proven"), result)
        return result

    @stage("unsat-core", "synthesize on an infeasible system with holes: unsat with a minimal core (E401)",
           needs=("loaded",), options={**holes, "infeasible": True}, sizes=synth_sizes, quick_sizes=(10,),
           chains_per_task=ONE_PER_FIVE)
    def unsat_core(inst: Instance) -> dict:
        r = synthesize(inst.loaded, objective="none")
        result = _synth_result(r)
        codes = [d.code for d in r.diagnostics]
        if r.status != "unsat" or "E401" not in codes:
            raise BenchmarkError(f"expected unsat with E401, got status {r.status} and {codes or 'no diagnostic'}",
                                 result)
        return result

    def gave_up(result: dict, evaluations: int, limit: int) -> None:
        holes_, log_space = result.pop("_space")
        result["evaluations"] = evaluations
        result["space"] = f"{holes_} holes, 10^{log_space:.1f} combinations"
        if result["status"] == "not found" and evaluations >= limit:
            result["status"] = f"gave up after {evaluations} evaluations (limit)"

    @stage("baseline-brute-force", "driver.brute_force(objective=\"none\"): unpruned enumeration of every "
           "candidate combination up to an evaluation limit", needs=("loaded", "unpruned_space"), options=holes,
           sizes=synth_sizes, chains_per_task=ONE_PER_FIVE, params={"limit": 200}, quick_params={"limit": 20})
    def baseline_brute_force(inst: Instance, limit: int) -> dict:
        r = brute_force(inst.loaded, objective="none", limit=limit)
        result = {"status": {"sat": "found", "unsat": "unsat (space exhausted)"}.get(r.status, "not found"),
                  "_space": inst.unpruned_space}
        gave_up(result, r.evaluated, limit)
        return result

    @stage("baseline-random-search", "random candidate combinations of the unpruned problem (fixed seed), each "
           "analysed by Problem.evaluate, until one is accepted or a limit", needs=("loaded", "unpruned_space"),
           options=holes, sizes=synth_sizes, chains_per_task=ONE_PER_FIVE, params={"limit": 200},
           quick_params={"limit": 20})
    def baseline_random_search(inst: Instance, limit: int) -> dict:
        problem = build_problem(inst.model, inst.scope, prune=False)
        names = list(problem.choices)
        counts = [len(problem.choices[n].candidates) for n in names]
        rng = random.Random(f"baseline-random-search/{inst.seed}")
        result = {"status": "not found", "_space": inst.unpruned_space}
        evaluations = 0
        if all(counts):
            while evaluations < limit:
                evaluations += 1
                config = Config(tuple((n, rng.randrange(k)) for n, k in zip(names, counts)))
                if problem.evaluate(config).accepted:
                    result["status"] = "found"
                    break
        gave_up(result, evaluations, limit)
        return result

    @stage("baseline-z3-direct", "the solver loop of synthesize (objective utilisation) on the problem built "
           "without pruning (build_problem(prune=False))", needs=("model", "scope"), options=holes,
           sizes=synth_sizes, chains_per_task=ONE_PER_FIVE, params={"objective": "utilisation"})
    def baseline_z3_direct(inst: Instance, objective: str) -> dict:
        model = inst.model
        goals = parse_objective(objective, model)
        budget = Budget(DEFAULT_RLIMIT, None)
        problem = build_problem(model, inst.scope, prune=False)
        result: dict = {"objective": objective, "holes": len(problem.choices)}
        if problem.infeasible is not None:
            result.update(status="unsat", reason=problem.infeasible)
            return result
        enc = problem.encoding(z3.Context())
        engine = Engine(problem, enc, budget)
        out = engine.run(objectives_for(goals, enc))
        status = {"optimal": "sat", "unknown": "undecided"}.get(out.status, out.status)
        result["status"] = status
        if out.config is not None:
            result["optimal"] = "yes" if out.status == "optimal" or (out.status == "sat" and not goals) else "no"
            label = "" if out.status != "unknown" else "best found "
            result.update({label + g.name: _objective_text(g, goal_value(g, out.evaluation.result)) for g in goals})
        result.update({"solver calls": engine.stats.checks, "analyses": problem.analyses, "rlimit": budget.used})
        if out.status == "unknown":
            result["reason"] = out.reason or budget.reason
        return result


_register_parsers()
_register_analyze()
_register_hostile()
_register_prove()
_register_synth()
startup.register(stage, BenchmarkError)
ros1.register(stage, BenchmarkError, UNAVAILABLE)
ros2.register(stage, BenchmarkError, UNAVAILABLE)
lsp.register(stage, BenchmarkError, UNAVAILABLE)
tightness.register(stage, BenchmarkError, UNAVAILABLE)
trace.register(stage, BenchmarkError, UNAVAILABLE)


# ------------------------------------------------------------------------------ measuring


def _summary(values: list) -> dict:
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def _run(fn: Callable[..., object], inst: Instance, params: dict,
         check: Callable[..., dict | None] | None = None) -> tuple[float, object]:
    start = time.perf_counter()
    try:
        result = fn(inst, **params)
    except BenchmarkError as err:
        err.seconds = time.perf_counter() - start
        raise
    elapsed = time.perf_counter() - start
    if check is not None:  # untimed
        try:
            result = check(inst, result)
        except BenchmarkError as err:
            err.seconds = elapsed
            raise
    return elapsed, result


def prepare(name: str, inst: Instance) -> None:
    setup = SETUPS.get(name)
    if setup is not None:
        setup()
    for attr in ("text",) + NEEDS[name]:
        getattr(inst, attr)


def measure(name: str, inst: Instance, repeat: int, memory: bool = True, budget: float | None = None,
            params: dict | None = None) -> dict:
    """Run stage ``name`` on ``inst``: ``repeat`` timed runs, then ``repeat`` traced runs. A run that takes
    longer than ``budget`` seconds ends the repetitions of its kind (the row says how many ran)."""
    fn = STAGES[name]
    params = PARAMS[name] if params is None else params
    prepare(name, inst)
    seconds, peaks = [], []
    outcome = None
    for _ in range(repeat):
        gc.collect()
        elapsed, result = _run(fn, inst, params, CHECKS.get(name))
        seconds.append(elapsed)
        outcome = result if isinstance(result, dict) else outcome
        del result
        if budget is not None and seconds[-1] > budget:
            break
    if memory:
        for _ in range(repeat):
            gc.collect()
            start = time.perf_counter()
            tracemalloc.start()
            try:
                fn(inst, **params)
                peaks.append(tracemalloc.get_traced_memory()[1])
            finally:
                tracemalloc.stop()
            if budget is not None and time.perf_counter() - start > budget:
                break
    row = {"stage": name, "tasks": inst.n_tasks, "seed": inst.seed, "chains": inst.chain_count,
           "lines": inst.text.count("\n"), "options": {k: str(v) for k, v in inst.options.items()},
           "params": params, "runs": len(seconds), "generate_seconds": inst.generate_seconds,
           "seconds": seconds, "seconds_summary": _summary(seconds)}
    if outcome is not None:
        row["result"] = outcome
    if peaks:
        row.update(memory_runs=len(peaks), peak_bytes=peaks, peak_bytes_summary=_summary(peaks))
    return row


def _merge(row: dict, more: dict) -> dict:
    """The row of a stage's repetitions so far (``row``) and of one more (``more``), both from ``measure``."""
    merged = dict(more)
    merged["seconds"] = row["seconds"] + more["seconds"]
    merged["runs"] = len(merged["seconds"])
    merged["seconds_summary"] = _summary(merged["seconds"])
    if "peak_bytes" in row or "peak_bytes" in more:
        merged["peak_bytes"] = row.get("peak_bytes", []) + more.get("peak_bytes", [])
        merged["memory_runs"] = len(merged["peak_bytes"])
        merged["peak_bytes_summary"] = _summary(merged["peak_bytes"])
    if "result" not in more and "result" in row:
        merged["result"] = row["result"]
    return merged


def profile(name: str, inst: Instance, path: Path, top: int = 30, params: dict | None = None) -> str:
    """One run of stage ``name`` under cProfile; the top functions by cumulative time, also written to
    ``path``. A stage that ends in a BenchmarkError is profiled all the same (its work was real)."""
    import cProfile
    import io
    import pstats

    params = PARAMS[name] if params is None else params
    prepare(name, inst)
    profiler = cProfile.Profile()
    note = ""
    try:
        profiler.runcall(STAGES[name], inst, **params)
    except BenchmarkError as err:
        note = f"(the run ended in an error row: {err})\n"
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats("cumulative").print_stats(top)
    text = f"cProfile of stage {name} on {inst.n_tasks} tasks (seed {inst.seed}), top {top} by cumulative time\n"
    text += note + out.getvalue()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return text


def machine() -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        load = round(os.getloadavg()[0], 2)
    except OSError:
        load = None
    return {"date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC"), "nproc": os.cpu_count(),
            "cpu": cpu, "python": platform.python_version(), "platform": platform.platform(),
            "loadavg_1min": load, **revision()}


def revision() -> dict:
    """The git commit of the measured code and the files of ``verify/`` changed since (numbers of a
    dirty tree are those of the working tree, not of the commit); empty without git."""
    import subprocess

    root = Path(__file__).resolve().parent.parent
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True,
                                timeout=10, check=True).stdout.strip()
        status = subprocess.run(["git", "status", "--porcelain", "--", "verify"], cwd=root, capture_output=True,
                                text=True, timeout=10, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return {}
    return {"commit": commit, "verify_changed": sorted(line[3:] for line in status.splitlines() if line.strip())}


# ------------------------------------------------------------------------------ reporting


def _seconds(x: float) -> str:
    return f"{x * 1000:.1f} ms" if x < 1 else f"{x:.2f} s"


def _bytes(x: int) -> str:
    return f"{x / 2**20:.1f} MiB" if x >= 2**20 else f"{x / 2**10:.0f} KiB"


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def result_text(result: dict | None) -> str:
    if not result:
        return ""
    return "; ".join(f"{k} {v}" if k != "status" else str(v) for k, v in result.items())


def markdown(rows: list[dict]) -> str:
    head = ("| stage | tasks | chains | lines | runs | time (median) | time (min–max) | peak memory (median) "
            "| peak memory (min–max) | result |")
    out = [head, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        if "error" in r or "skipped" in r:
            if "error" in r:
                what = f"error: {r['error']}" + (f" (after {_seconds(r['seconds'][0])})" if r.get("seconds") else "")
            else:
                what = f"skipped: {r['skipped']}"
            out.append(f"| {r['stage']} | {r['tasks']} | {r.get('chains', '')} | {r.get('lines', '')} | 0 | "
                       f"{_cell(what)} | | | | {_cell(result_text(r.get('result')))} |")
            continue
        t = r["seconds_summary"]
        m = r.get("peak_bytes_summary")
        mem = (_bytes(m["median"]), f"{_bytes(m['min'])} – {_bytes(m['max'])}") if m else ("–", "–")
        runs = f"{r['runs']}" + (f" (+{r['memory_runs']} traced)" if m else "")
        out.append(f"| {r['stage']} | {r['tasks']} | {r['chains']} | {r['lines']} | {runs} | "
                   f"{_seconds(t['median'])} | {_seconds(t['min'])} – {_seconds(t['max'])} | {mem[0]} | {mem[1]} | "
                   f"{_cell(result_text(r.get('result')))} |")
    return "\n".join(out)


# ------------------------------------------------------------------------------ command line


def stage_params(name: str, quick: bool, overrides: dict[str, str] | None = None) -> dict:
    """The parameters of stage ``name`` (its quick ones with ``quick``), with the ``--param`` values of the
    keys it has, each read as the type of its default (ValueError if it is not one)."""
    params = dict(QUICK_PARAMS[name] if quick else PARAMS[name])
    for key, text in (overrides or {}).items():
        if key not in params:
            continue
        default = params[key]
        if isinstance(default, bool):
            if text.lower() not in ("true", "false", "yes", "no", "1", "0"):
                raise ValueError(f"not a boolean: {text!r}")
            params[key] = text.lower() in ("true", "yes", "1")
        elif isinstance(default, (int, float, Fraction)):
            params[key] = type(default)(text)
        else:
            params[key] = text
    return params


def _sizes(text: str) -> list[int]:
    try:
        sizes = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of task counts: {text!r}") from None
    if not sizes or min(sizes) < 1:
        raise argparse.ArgumentTypeError("sizes must be positive task counts")
    return sizes


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks", description="Time verify's stages on generated "
                                "WATERS-2015-like systems of several sizes.")
    p.add_argument("--sizes", type=_sizes, help="task counts for every stage (default: each stage's own; "
                   "see --list)")
    p.add_argument("--repeat", type=int, help="repetitions per stage and size (default 3)")
    p.add_argument("--stages", help="comma-separated stage names (default: every available stage)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--chains", type=int, default=None,
                   help="chains per system, for every stage on WATERS systems (default: the stage's own, "
                        "one per five tasks for prove and synth stages, else WATERS' 30-60)")
    p.add_argument("--quick", action="store_true", help="each stage's tiny sizes and parameters, one repetition")
    p.add_argument("--no-memory", action="store_true", help="skip the tracemalloc runs")
    p.add_argument("--budget", type=float, default=60.0,
                   help="seconds: a run longer than this ends its repetitions, and a size that would take "
                        "longer even with linear growth from the last one is skipped (default 60; 0: no limit)")
    p.add_argument("--profile", nargs="?", const="all", default=None, metavar="STAGES",
                   help="also profile stages once at their largest measured size (cProfile, written next "
                        "to --out as profile-STAGE-TASKS.txt): every stage, or the comma-separated STAGES")
    p.add_argument("--interleave", action="store_true",
                   help="measure size by size, the selected stages one repetition each in turn (stages compared "
                        "with each other then share the machine's state: load, the instances alive)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="set parameter KEY of every selected stage that has one (e.g. gc=on for the parse-* "
                        "stages, limit=50 for the baselines); repeatable")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"JSON results (default {DEFAULT_OUT})")
    p.add_argument("--list", action="store_true", help="list the stages and exit")
    args = p.parse_args(argv)

    if args.list:
        for name in STAGES:
            sizes = ",".join(map(str, SIZES[name]))
            print(f"{name}: {DESCRIPTIONS[name]} [sizes {sizes}; quick {','.join(map(str, QUICK[name]))}]")
        for name, why in UNAVAILABLE.items():
            print(f"{name}: unavailable: {why}")
        return 0
    repeat = args.repeat if args.repeat is not None else 1 if args.quick else 3
    if repeat < 1:
        p.error("--repeat must be at least 1")
    if args.chains is not None and args.chains < 0:
        p.error("--chains must be at least 0")
    names = [s.strip() for s in args.stages.split(",")] if args.stages else list(STAGES)
    for name in names:
        if name not in STAGES:
            why = UNAVAILABLE.get(name, "known stages: " + ", ".join(list(STAGES) + list(UNAVAILABLE)))
            p.error(f"stage {name!r} is not available: {why}")
    to_profile = set(names) if args.profile == "all" else \
        {s.strip() for s in args.profile.split(",")} if args.profile else set()
    for name in to_profile - set(names):
        p.error(f"--profile {name!r}: not among the stages run")
    overrides: dict[str, str] = {}
    for item in args.param:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            p.error(f"--param {item!r}: expected KEY=VALUE")
        overrides[key.strip()] = value.strip()
    for key, value in overrides.items():
        having = [n for n in names if key in (QUICK_PARAMS[n] if args.quick else PARAMS[n])]
        if not having:
            p.error(f"--param {key}: no selected stage has a parameter {key!r}")
        try:
            for n in having:
                stage_params(n, args.quick, {key: value})
        except ValueError as err:
            p.error(f"--param {key}={value}: {err}")

    verify.load_text(generate_system(4, 0))  # warm-up, untimed: builds the parser once
    info = machine()
    dirty = f" + {len(info['verify_changed'])} changed file(s) in verify/" if info.get("verify_changed") else ""
    print(f"verify benchmarks — {info['date']}; {info['nproc']} CPUs ({info['cpu']}); Python {info['python']}; "
          f"load {info['loadavg_1min']}; commit {info.get('commit', '?')}{dirty}", file=sys.stderr)
    budget = args.budget or None
    instances: dict[tuple, Instance] = {}
    rows: list[dict] = []
    largest: dict[str, Instance] = {}
    stage_sizes = {name: list(args.sizes or (QUICK[name] if args.quick else SIZES[name])) for name in names}
    params_of = {name: stage_params(name, args.quick, overrides) for name in names}
    last: dict[str, tuple[int, float]] = {}  # stage -> (size, median seconds) of its last measured size
    failed = False
    jobs = [(name, size) for name in names for size in stage_sizes[name]]
    if args.interleave:  # every stage at one size, repetition by repetition, before the next size
        groups = [[job for job in jobs if job[1] == size] for size in sorted({size for _, size in jobs})]
    else:
        groups = [[job] for job in jobs]
    for group in groups:
        todo = []
        for name, size in group:
            if budget is not None and name in last and last[name][1] * size / last[name][0] > budget:
                done, took = last[name]
                rows.append({"stage": name, "tasks": size, "seed": args.seed,
                             "skipped": f"{done} tasks took {took:.1f} s; even linear growth exceeds "
                                        f"the budget of {args.budget:g} s"})
                last[name] = (size, took * size / done)
                continue
            chains = chains_for(name, size, args.chains)
            inst = instances.setdefault(instance_key(name, size, chains),
                                        Instance(size, args.seed, OPTIONS[name], chains, GENERATORS[name]))
            todo.append((name, size, inst))
        measured: dict[str, dict] = {}  # stage -> its row so far (its repetitions merged when interleaved)
        for rep in range(repeat if args.interleave else 1):
            for name, size, inst in todo:
                so_far = measured.get(name)
                if so_far is not None and ("error" in so_far or (budget is not None
                                                                 and so_far["seconds"][-1] > budget)):
                    continue  # failed, or its repetitions ended
                print(f"  {name} on {size} tasks" + (f" (repetition {rep + 1})" if args.interleave else "")
                      + " ...", file=sys.stderr, flush=True)
                try:
                    row = measure(name, inst, 1 if args.interleave else repeat, memory=not args.no_memory,
                                  budget=budget, params=params_of[name])
                except Exception as err:  # recorded, and the run goes on with the other stages and sizes
                    what = str(err) if isinstance(err, BenchmarkError) else f"{type(err).__name__}: {err}"
                    row = {"stage": name, "tasks": size, "seed": args.seed, "error": what, "params": params_of[name]}
                    if "text" in inst.__dict__:
                        row.update(chains=inst.chain_count, lines=inst.text.count("\n"))
                    if isinstance(err, BenchmarkError):
                        row["result"] = err.result
                        if err.seconds is not None:
                            row["seconds"] = [err.seconds]
                    print(f"    error: {what}", file=sys.stderr, flush=True)
                measured[name] = row if so_far is None or "error" in row else _merge(so_far, row)
        for name, size, inst in todo:
            row = measured[name]
            rows.append(row)
            if "error" in row:
                failed = True
                if row.get("seconds"):
                    largest[name] = inst
                    last[name] = (size, row["seconds"][0])
            else:
                largest[name] = inst
                last[name] = (size, row["seconds_summary"]["median"])
    profiles = {}
    for name, inst in largest.items():
        if name not in to_profile:
            continue
        path = args.out.parent / f"profile-{name.replace('+', '-')}-{inst.n_tasks}.txt"
        print(f"  profiling {name} on {inst.n_tasks} tasks -> {path}", file=sys.stderr, flush=True)
        profile(name, inst, path, params=stage_params(name, args.quick, overrides))
        profiles[name] = str(path)
    table = markdown(rows)
    print(table)
    doc = {"schema": SCHEMA, "machine": info,
           "config": {"sizes": stage_sizes, "repeat": repeat, "seed": args.seed, "chains": args.chains,
                      "memory": not args.no_memory, "budget": args.budget, "quick": args.quick, "stages": names,
                      "interleave": args.interleave, "params": overrides},
           "unavailable": UNAVAILABLE, "results": rows, "profiles": profiles, "markdown": table}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(doc, indent=2, default=_json_default) + "\n", encoding="utf-8")
    print(f"results written to {args.out}", file=sys.stderr)
    return 1 if failed else 0


def _json_default(value):
    if isinstance(value, Fraction):
        return str(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
