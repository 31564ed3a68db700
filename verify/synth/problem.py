"""One synthesis problem: statements, choices (pruned unless tracked), structure, scale and seed.

``build_problem`` does everything that happens before the solver runs: it collects the user's
statements, builds every choice's candidates, prunes them exactly (untracked problems only), finds
the trigger structure and the dependency cones, picks the tick and the rate scale, and analyses one
*seed* configuration — every choice at its slowest candidate (tracked: every ``wcet`` relaxed too) —
whose response times are valid lower bounds wherever the decisions are at least as fast
(specs/synthesis.md §4), and exact for tasks whose cone holds no decision.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING
from collections.abc import Mapping

from ..core.diagnostics import Diagnostic
from ..model.system import ActivationModel, SystemModel
from ..frontend.resolve import SystemScope
from ..timing import AnalysisResult, analyze
from .candidates import Candidate, Choice, build_choices, make_choice
from .prune import Pruner
from .statements import Statement, collect_statements, configured_model, statement_index
from .structure import Structure, analyse_structure, topological, trigger_graph

if TYPE_CHECKING:
    import z3

    from .encode import Encoding




def rejects(d: Diagnostic) -> bool:
    """Whether a diagnostic of the analysis rejects a configuration: every error, and a deadline that its
    bound does not prove (E316, a warning for `analyze`): synth returns only configurations whose
    deadlines the analysis proves, as its encoding asks ``R ≤ deadline`` (specs/synthesis.md)."""
    return d.severity.value == "error" or d.code == "E316"

@dataclass(frozen=True)
class Config:
    """A candidate index per choice, and the tracked statements that are off (relaxed)."""

    choice: tuple[tuple[str, int], ...]
    off: frozenset[str] = frozenset()

    def index(self, task: str) -> int:
        return dict(self.choice)[task]


@dataclass(frozen=True)
class Evaluation:
    """The independent analysis of one configuration and its verdict."""

    model: SystemModel
    result: AnalysisResult
    accepted: bool
    reasons: tuple[str, ...]


@dataclass
class Problem:
    model: SystemModel
    scope: SystemScope | None
    statements: tuple[Statement, ...]
    choices: dict[str, Choice]
    structure: Structure
    atoms: list[tuple[str, str]]  # bit index -> ("choice", task) | ("wcet", key) | ("core", key)
    tracked: bool
    pruned: int = 0
    infeasible: str | None = None
    culprit: tuple[tuple[str, ...], tuple[str, ...]] | None = None  # (chains, tasks) pruning blamed
    analyses: int = field(default=0)
    _seed: tuple[Config, Evaluation] | None = field(default=None, repr=False)
    _cache: dict[Config, Evaluation] = field(default_factory=dict, repr=False)

    def candidates(self, config: Config) -> dict[str, Candidate]:
        return {tid: self.choices[tid].candidates[i] for tid, i in config.choice}

    def activations(self, config: Config) -> dict[str, ActivationModel]:
        """The activation ``config`` chooses per task id."""
        return {tid: self.choices[tid].candidates[i].activation for tid, i in config.choice}

    def configured(self, config: Config) -> SystemModel:
        return configured_model(self.model, self.activations(config), self.statements, config.off)

    def evaluate(self, config: Config) -> Evaluation:
        """Analyse a configuration (specs/timing.md §5–§7): accepted when the analysis reports no
        error, every deadline is proved by its bound (no E316) and every spec holds."""
        if config in self._cache:
            return self._cache[config]
        model = self.configured(config)
        result = analyze(model)
        self.analyses += 1
        reasons = [f"{d.code}: {d.message}" for d in result.diagnostics if rejects(d)]
        for chain in result.chains:
            reasons += [f"chain `{chain.name}`: {c.kind} bound exceeds its spec" for c in chain.specs if not c.ok]
        self._cache[config] = Evaluation(model, result, not reasons, tuple(reasons))
        return self._cache[config]

    def seed(self) -> tuple[Config, Evaluation]:
        """The seed configuration and its analysis (computed once)."""
        if self._seed is None:
            config = self.seed_config()
            self._seed = (config, self.evaluate(config))
        return self._seed

    def encoding(self, ctx: z3.Context) -> Encoding:
        from .encode import Encoding

        _, ev = self.seed()
        seed_r = {t.id: t.wcrt for t in ev.result.tasks}
        return Encoding(self.model, self.choices, self.statements, self.structure, self.tracked, seed_r, ctx)

    def seed_config(self) -> Config:
        off = frozenset(st.key for st in self.statements if st.kind == "wcet") if self.tracked else frozenset()
        return Config(tuple((tid, ch.slowest) for tid, ch in self.choices.items()), off)


def build_problem(model: SystemModel, scope: SystemScope | None = None, *, tracked: bool = False,
                  prune: bool = True) -> Problem:
    statements = collect_statements(model, scope)
    choices = build_choices(model, scope, statements, tracked)
    return problem_of(model, scope, statements, choices, tracked=tracked, prune=prune)


def relaxed_problem(problem: Problem, off: frozenset[str]) -> Problem:
    """The untracked, pruned problem of a tracked ``problem`` with the statements in ``off`` relaxed
    and every other one in force: the model relaxed as ``configured_model`` does, each choice reduced
    to the candidates no statement in force forbids (specs/synthesis.md §6). Its configurations are
    exactly the tracked problem's configurations with that ``off`` set."""
    model = configured_model(problem.model, {}, problem.statements, off)
    choices = {}
    for tid, ch in problem.choices.items():
        keep = ch.allowed(off)
        choices[tid] = make_choice(tid, tuple(ch.candidates[i] for i in keep), tuple(() for _ in keep), ch.hole)
    return problem_of(model, problem.scope, problem.statements, choices, tracked=False, prune=True)


def starvation(model: SystemModel) -> str | None:
    """Why no configuration is accepted when a callback can starve in its mutually exclusive group
    (specs/timing.md §9.4): its group, not a choice, decides that it has no bound (E312)."""
    from ..timing.multithreaded import group_blocking

    for ex in model.executors:
        if ex.multi_threaded:
            for t in model.callbacks(ex.name):
                blocking, why = group_blocking(model, t, ex)
                if blocking is None:
                    return (f"callback `{t.id}` has no bound in any configuration (E312): {why}; give it a "
                            "callback group of its own or a reentrant one")
    return None


def problem_of(model: SystemModel, scope: SystemScope | None, statements: tuple[Statement, ...],
               choices: dict[str, Choice], *, tracked: bool, prune: bool) -> Problem:
    pruned, infeasible, culprit = 0, None, None
    if not tracked and prune:
        graph, _ = trigger_graph(model, choices)
        order, cyclic = topological(graph)
        pruner = Pruner(model, choices, order, cyclic)
        choices = pruner.run()
        pruned, infeasible, culprit = pruner.removed, pruner.infeasible, pruner.culprit
    if infeasible is None and any(not ch.candidates for ch in choices.values()):
        infeasible = "a hole has no candidate"
    if infeasible is None:
        infeasible = starvation(model)
    atoms, bits = _atoms(model, choices, statements, tracked)
    structure = analyse_structure(model, choices, bits)
    return Problem(model, scope, statements, choices, structure, atoms, tracked, pruned, infeasible, culprit)


def _atoms(model: SystemModel, choices: Mapping[str, Choice], statements: tuple[Statement, ...],
           tracked: bool) -> tuple[list[tuple[str, str]], dict[str, int]]:
    """The decisions a response time can depend on, as bit positions, and each task's own bits."""
    atoms: list[tuple[str, str]] = [("choice", tid) for tid in choices]
    position = {a: i for i, a in enumerate(atoms)}
    if tracked:
        for st in statements:
            if st.kind in ("wcet", "core"):
                position[(st.kind, st.key)] = len(atoms)
                atoms.append((st.kind, st.key))
    slots = statement_index(statements)
    bits: dict[str, int] = {}
    for t in model.tasks:
        value = 1 << position[("choice", t.id)] if t.id in choices else 0
        if tracked:
            for kind in ("wcet", "core"):
                key = slots.get(t.id, {}).get(kind)
                if key is not None:
                    value |= 1 << position[(kind, key)]
        bits[t.id] = value
    return atoms, bits

