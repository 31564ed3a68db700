"""The performance work changes no output: front end and timing analysis against recorded digests.

The digests in ``tests/golden/perf`` were recorded with the implementation before the performance
work (Lark's tree + transformer, Fraction arithmetic throughout the response-time analysis). Each is
the SHA-256 of ``perf_cases.dump`` of a result: the typed trees with every span, the semantic models
and all diagnostics of ``verify.load_text``, and every field of ``verify.timing.analyze`` in both
data-age variants. Run with ``UPDATE_GOLDEN=1`` to rewrite them — only when an output is *meant* to
change, never to make a speed-up pass.
"""
from __future__ import annotations

import json
import os

import pytest

import verify
from verify.timing import analyze

from .conftest import EXAMPLES, ROOT
from .perf_cases import analysis_cases, digest, dump, load_cases

GOLDEN = ROOT / "tests" / "golden" / "perf"
UPDATE = os.environ.get("UPDATE_GOLDEN") == "1"

LOAD_CASES = load_cases()
ANALYSIS_CASES = analysis_cases()


def _golden(name: str) -> dict:
    path = GOLDEN / name
    return json.loads(path.read_text()) if path.exists() else {}


LOAD_GOLDEN = _golden("load.json")
ANALYSIS_GOLDEN = _golden("analysis.json")


def _load_digest(name: str, text: str) -> str:
    result = verify.load_text(text, name)
    return digest([result.project.modules, result.diagnostics, result.models])


def _model(name: str, text: str):
    if name == "navigation":
        result = verify.load(str(EXAMPLES / "navigation" / "navigation.vfy"))
    else:
        result = verify.load_text(text, name + ".vfy")
    assert result.ok, [(d.code, d.message) for d in result.diagnostics][:5]
    return result.system()


def _analysis_digests(name: str, text: str) -> dict[str, str]:
    model = _model(name, text)
    return {variant: digest(analyze(model, data_age=variant), root=str(ROOT))
            for variant in ("reduced", "non-reduced")}


@pytest.mark.parametrize("name", sorted(LOAD_CASES))
def test_front_end_output_unchanged(name):
    got = _load_digest(name, LOAD_CASES[name])
    if UPDATE:
        LOAD_GOLDEN[name] = got
        return
    assert got == LOAD_GOLDEN[name]


@pytest.mark.parametrize("name", sorted(ANALYSIS_CASES))
def test_analysis_output_unchanged(name):
    got = _analysis_digests(name, ANALYSIS_CASES[name])
    if UPDATE:
        ANALYSIS_GOLDEN[name] = got
        return
    assert got == ANALYSIS_GOLDEN[name]


def teardown_module():
    if UPDATE:
        GOLDEN.mkdir(parents=True, exist_ok=True)
        for file, data in (("load.json", LOAD_GOLDEN), ("analysis.json", ANALYSIS_GOLDEN)):
            (GOLDEN / file).write_text(json.dumps(dict(sorted(data.items())), indent=1) + "\n")


# ------------------------------------------------------------------ the parser's fast path against Lark

def _both_paths(text: str):
    """(fast result or None if the fast path left the text to Lark, Lark's result, Lark's diagnostics)."""
    from verify.core.diagnostics import DiagnosticSink
    from verify.frontend.fastparse import Unparsable
    from verify.frontend.parse import fast_parser
    from verify.frontend.recovery import recover
    from verify.frontend.treebuild import NumberError, TreeBuilder

    sink = DiagnosticSink()
    slow = recover(text, "t.vfy", sink).module
    try:
        builder = TreeBuilder("t.vfy", DiagnosticSink())
        fast = fast_parser().parse(text, builder.callbacks(fast_parser().callback_names()), builder.tokens())
    except (Unparsable, NumberError):
        fast = None
    return fast, slow, sink.items


def _assert_fast_path_exact(text: str) -> bool:
    fast, slow, diagnostics = _both_paths(text)
    if fast is not None:  # whatever the fast path accepts, Lark accepts, with the same tree and spans
        assert not diagnostics and slow is not None, (text, diagnostics)
        assert dump(fast) == dump(slow)
    return fast is not None


def test_the_fast_path_is_enabled_for_the_grammar():
    from verify.frontend.parse import fast_parser

    assert fast_parser() is not None


@pytest.mark.parametrize("text", [
    "component task { in timer : in task in { wcet 1 ms } }",
    "componentX { }", "component C { task T { wcet 1ms } }", "component C {} /* a */ /* b */",
    "/* \" */ x\" */", "// c\n#", "system S { core c chain k: a.b .. c.d }", "import \"a\" import\"b\"",
    "component C { in a = b & c & d activation 1 ms .. 2 ms fixed }",
    "system S { instance i : C on c { task T timer ? in 1 ms .. 2 ms step 1/3 ms } }",
    "system S { instance i:C{task T priority 1 on c trigger p every ? in 1 .. 3 wcrt 1 s deadline 2 s} }",
    "component C { task T { reads x optional oversampling <= 2 undersampling forbidden produces a, b } }",
    "", "   ", "// only a comment", "component C { task T { wcet 1 msx } }", "system S { core c policy fifo }",
    "component C { task T { wcet 00000000000000000000000000000000000000001 ms } }",
    "component C { task T { wcet 1/0 ms } }",
])
def test_fast_path_agrees_with_lark_on_corner_cases(text):
    _assert_fast_path_exact(text)


def test_fast_path_decides_the_benchmark_systems_and_agrees():
    for name in ("waters-100-holes", "waters-100-infeasible", "waters-300", "navigation.vfy", "components.vfy"):
        assert _assert_fast_path_exact(LOAD_CASES[name]), name


@pytest.mark.slow
def test_fast_path_agrees_with_lark_on_mutants():
    for _name, text in LOAD_CASES.items():
        _assert_fast_path_exact(text)


try:
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from verify.frontend.fmt import format_module

    from .strategies import modules

    @pytest.mark.slow
    @settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(modules, st.randoms(use_true_random=False))
    def test_fast_path_agrees_with_lark_on_random_modules(module, rng):
        from .perf_cases import mutate

        text = format_module(module)
        assert _assert_fast_path_exact(text)
        _assert_fast_path_exact(mutate(text, rng))
        _assert_fast_path_exact(mutate(text, rng, semantic=True))

    @settings(max_examples=300, deadline=None)
    @given(st.lists(st.sampled_from(list("abcms{}:;.->?&|\"/*0123456789 \n\tinkHz_<=,") + [
        "task ", "in ", "component ", "system ", "timer ", "on ", "// ", "/* ", "*/", " ms", "..", "1/3"]),
        max_size=60).map("".join))
    def test_fast_path_agrees_with_lark_on_random_text(text):
        _assert_fast_path_exact(text)
except ImportError:  # pragma: no cover - hypothesis is a test dependency
    pass


# ------------------------------------------------------------------ fastrta against the reference, round by round

def _rounds_agree(model, max_rounds: int = 6) -> None:
    """Every CPA round of ``fastrta`` equals ``reference.response_times`` (the reference statement)."""
    from verify.timing import fastrta, reference
    from verify.timing.rates import activation_rates, event_models, trigger_order

    order = trigger_order(model)
    infos = activation_rates(model, order)
    bcrt = {t.id: t.bcet for t in model.tasks}
    wcrt = {t.id: (t.wcrt_bound if t.wcrt_bound is not None else t.bcet) for t in model.tasks}
    static = fastrta.Static(model)
    memo: dict = {}
    analysed = None
    for _ in range(max_rounds):
        events = event_models(model, infos, order[0], wcrt, bcrt, memo)
        assert events == event_models(model, infos, order[0], wcrt, bcrt)
        expected = reference.response_times(model, events, wcrt)
        analysed = fastrta.Round(static, events, wcrt, analysed)  # with what it reuses from the last round
        assert dump(analysed.responses()) == dump(expected)
        assert dump(fastrta.Round(static, events, wcrt).responses()) == dump(expected)
        new = {tid: r.wcrt for tid, r in expected.items()}
        assert analysed.wcrts() == new
        if new == wcrt:
            return
        wcrt = new


try:
    from .test_bounds_vs_simulation import systems as random_systems

    @pytest.mark.slow
    @settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(random_systems())
    def test_fast_rounds_agree_with_rta_on_random_systems(text):
        result = verify.load_text(text, "random.vfy")
        assert result.ok
        _rounds_agree(result.system())

    @pytest.mark.slow
    @settings(max_examples=60, deadline=None)
    @given(st.integers(1, 10**6), st.integers(3, 40), st.integers(1, 4))
    def test_fast_rounds_agree_with_rta_on_cooperative_systems(seed, n, load):
        from .perf_cases import coop_system

        result = verify.load_text(coop_system(seed, n, load), "coop.vfy")
        if result.ok:
            _rounds_agree(result.system())
except ImportError:  # pragma: no cover
    pass


def test_trigger_order_is_networkx_order_on_random_graphs():
    import random

    import networkx as nx

    from verify.timing.rates import graph_order

    for seed in range(400):
        rng = random.Random(seed)
        n = rng.randint(1, 14)
        successors = [[rng.randrange(n) for _ in range(rng.choice([0, 0, 1, 1, 2, 3]))] for _ in range(n)]
        graph = nx.DiGraph()
        graph.add_nodes_from(range(n))
        graph.add_edges_from((w, i) for w in range(n) for i in successors[w])
        cyclic = set()
        for comp in nx.strongly_connected_components(graph):
            if len(comp) > 1 or any(graph.has_edge(v, v) for v in comp):
                cyclic |= comp
        condensed = nx.condensation(graph)
        expected = []
        for scc in nx.lexicographical_topological_sort(condensed, key=lambda c: min(condensed.nodes[c]["members"])):
            expected.extend(sorted(condensed.nodes[scc]["members"]))
        assert graph_order(successors) == (expected, cyclic)
