"""Parser engines for the ``parse-*`` stages of ``benchmarks.run``: verify's own parse against Lark's.

Every engine turns the text of a valid model into the same ``verify.model.syntax.Module`` with the same
``TreeBuilder`` callbacks of ``verify.frontend.parse`` (one per grammar rule, ``(start, end, children)`` with positions
``fastparse.position(line, column)``), so that what is compared is the machinery around them:

- ``verify``: ``verify.frontend.parse.parse_source`` — the fast path of ``verify/frontend/fastparse.py``
  (Lark's table, a one-regex
  lexer, callbacks at each reduction);
- ``lark-transformer``: ``Lark(..., parser="lalr", lexer="contextual", transformer=T)``, Lark's own tree-less
  LALR: Lark calls ``T``'s methods at each reduction and builds no tree;
- ``lark-standalone``: the same with the parser that ``python -m lark.tools.standalone`` generates (written
  to ``benchmarks/out/`` at benchmark time, never committed) and the same transformer;
- ``lark-tree``: Lark's parse tree, then ``TreeBuilder.transform`` (what ``verify.frontend.recovery`` does on its
  error path; a reference, not a candidate).

**Positions with a transformer.** Lark passes an internal transformer no ``meta`` (``v_args(meta=True)``
raises "Meta args not supported for internal transformer") and ``propagate_positions`` sets positions only
on ``Tree`` results. So both Lark engines are built with ``keep_all_tokens=True`` (the table and the lexer
are the same; a rule's callback also receives its keywords and punctuation) and ``propagate_positions=False``,
and the adapter (``transformer``) does what Lark's position rule does: a node spans from the start of its first
child to the end of its last one, anonymous tokens included; each value travels up as ``(value, start, end)``.
It then drops the anonymous tokens (the terminals the ordinary parser filters out: keywords, punctuation) and
converts the kept ones with ``TreeBuilder.tokens()``, and calls the builder's callback. Lark's own inlining of
``_rule``/``x*`` helpers (a ``Tree`` per helper reduction, spliced by the parent) and ``?rule`` expansion are
left as Lark does them.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import subprocess
import sys
import tempfile
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"


def dropped_terminals() -> frozenset[str]:
    """The terminals the ordinary parser (``verify.frontend.grammar.lark_parser``) leaves out of its trees."""
    from verify.frontend.grammar import lark_parser

    dropped, kept = set(), set()
    for rule in lark_parser().rules:
        for sym in rule.expansion:
            if sym.is_term:
                (dropped if sym.filter_out else kept).add(str(sym.name))
    if dropped & kept:  # pragma: no cover - a terminal both kept and dropped: the adapter cannot tell by type
        raise RuntimeError(f"terminals both kept and filtered out: {sorted(dropped & kept)}")
    return frozenset(dropped)


def callback_names() -> list[str]:
    """The rules (aliases or names) that build a value: every method of ``TreeBuilder`` a rule calls."""
    from verify.frontend.parse import fast_parser

    fast = fast_parser()
    if fast is None:  # pragma: no cover - the fast path is off for this grammar
        raise RuntimeError("verify's fast path (verify/frontend/fastparse.py) is disabled for this grammar")
    return sorted(fast.callback_names())


def transformer(transformer_class: type):
    """An instance of a subclass of ``transformer_class`` (``lark.Transformer``, or the standalone module's
    copy of it) that builds ``verify.model.syntax`` with ``TreeBuilder``; ``begin(path)`` before each parse (a new
    builder: spans carry the path). Its parse returns ``(module, start, end)``."""
    from verify.core.diagnostics import DiagnosticSink
    from verify.frontend.treebuild import TreeBuilder

    names = callback_names()
    dropped = dropped_terminals()

    class BuildSyntax(transformer_class):
        def __init__(self):
            super().__init__(visit_tokens=False)
            self.callbacks: dict = {}
            self.tokens: dict = {}
            for name in names:  # Lark looks the callbacks up with getattr(transformer, rule alias or name)
                setattr(self, name, self._method(name))

        def begin(self, path: str) -> None:
            builder = TreeBuilder(path, DiagnosticSink())
            self.callbacks = {name: getattr(builder, name) for name in names}
            self.tokens = builder.tokens()

        def _method(self, name: str):
            state = self

            def build(children):
                kids = []
                append = kids.append
                tokens = state.tokens
                for c in children:
                    if c.__class__ is tuple:  # a value built below: (value, start, end)
                        append(c[0])
                    elif c.type not in dropped:
                        convert = tokens.get(c.type)
                        append(c.value if convert is None else
                               convert(c.value, c.line << 32 | c.column, c.end_line << 32 | c.end_column))
                if children:
                    first, last = children[0], children[-1]
                    start = first[1] if first.__class__ is tuple else first.line << 32 | first.column
                    end = last[2] if last.__class__ is tuple else last.end_line << 32 | last.end_column
                else:
                    start = end = None
                return state.callbacks[name](start, end, kids), start, end

            build.__name__ = name
            return build

    return BuildSyntax()


class LarkTransformerEngine:
    """Lark's LALR with the contextual lexer and ``transformer=``: no parse tree."""

    def __init__(self):
        from lark import Lark, Transformer

        from verify.frontend.grammar import WholeWords, grammar_text

        self.transformer = transformer(Transformer)
        self.lark = Lark(grammar_text(), parser="lalr", lexer="contextual", keep_all_tokens=True,
                         propagate_positions=False, postlex=WholeWords(), transformer=self.transformer)

    def parse(self, text: str, path: str):
        self.transformer.begin(path)
        return self.lark.parse(text)[0]


def generate_standalone(out_dir: Path = OUT) -> Path:
    """``python -m lark.tools.standalone`` on verify's grammar (``--keep_all_tokens``, contextual lexer), written
    to ``out_dir`` under a name that depends on the grammar and Lark's version (atomically: concurrent runs
    may share the directory). Regenerated at each call."""
    import lark

    from verify.frontend.grammar import grammar_text

    grammar = grammar_text()
    digest = hashlib.sha256(f"{lark.__version__}\n{grammar}".encode()).hexdigest()[:12]
    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / f"lark_standalone_{digest}.py"
    with tempfile.TemporaryDirectory(dir=out_dir) as tmp:
        grammar_path = Path(tmp) / "verify.lark"
        grammar_path.write_text(grammar, encoding="utf-8")
        code = Path(tmp) / target.name
        subprocess.run([sys.executable, "-m", "lark.tools.standalone", "--keep_all_tokens", "-s", "start",
                        "-l", "contextual", "-o", str(code), str(grammar_path)], check=True, capture_output=True,
                       text=True, timeout=300)
        os.replace(code, target)
    return target


class LarkStandaloneEngine:
    """The standalone parser Lark generates for the grammar, with the same transformer (built on the
    generated module's own ``Transformer``)."""

    def __init__(self, out_dir: Path = OUT):
        from verify.frontend.grammar import WholeWords

        self.path = generate_standalone(out_dir)
        spec = importlib.util.spec_from_file_location(f"verify_bench_{self.path.stem}", self.path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        self.module = module
        self.transformer = transformer(module.Transformer)
        self.lark = module.Lark_StandAlone(transformer=self.transformer, postlex=WholeWords(),
                                           propagate_positions=False)

    def parse(self, text: str, path: str):
        self.transformer.begin(path)
        return self.lark.parse(text)[0]


class LarkTreeEngine:
    """Lark's parse tree with positions (``verify.frontend.grammar.lark_parser()``), then ``TreeBuilder.transform``."""

    def __init__(self):
        from verify.frontend.grammar import lark_parser

        self.lark = lark_parser()

    def parse(self, text: str, path: str):
        from verify.core.diagnostics import DiagnosticSink
        from verify.frontend.treebuild import TreeBuilder

        return TreeBuilder(path, DiagnosticSink()).transform(self.lark.parse(text))


class VerifyEngine:
    """``verify.frontend.parse.parse_source``: the fast path of ``verify/frontend/fastparse.py`` on valid input."""

    def parse(self, text: str, path: str):
        from verify.frontend.parse import parse_source

        parsed = parse_source(text, path)
        if parsed.diagnostics or parsed.module is None:
            first = parsed.diagnostics[0] if parsed.diagnostics else None
            raise ValueError(f"{path}: {len(parsed.diagnostics)} diagnostic(s)"
                             + (f", first {first.code}: {first.message}" if first else ""))
        return parsed.module

    @staticmethod
    def fast_path(text: str, path: str):
        """The module straight from ``FastParser.parse`` (raises ``Unparsable`` if the fast path rejects the
        text, in which case ``parse_source`` would have timed Lark's error path instead)."""
        from verify.core.diagnostics import DiagnosticSink
        from verify.frontend.parse import fast_parser
        from verify.frontend.treebuild import TreeBuilder

        builder = TreeBuilder(path, DiagnosticSink())
        return fast_parser().parse(text, builder.callbacks(fast_parser().callback_names()), builder.tokens())


def sampled_spans(value, most: int = 200) -> list:
    """Every span in ``value`` (a syntax node), walking its fields as ``tests/perf_cases.dump`` does, except
    that a tuple of more than ``most`` nodes is sampled: its first, every k-th and its last node (about
    ``most`` of them). Spans take no part in ``==`` on syntax nodes; this list does."""
    import dataclasses

    from verify.core.source import Span

    out: list = []

    def walk(v):
        if isinstance(v, Span):
            out.append(v)
        elif dataclasses.is_dataclass(v) and not isinstance(v, type):
            for f in dataclasses.fields(v):
                walk(getattr(v, f.name))
        elif isinstance(v, (tuple, list)):
            if len(v) > most:
                step = -(-len(v) // most)
                v = list(v[::step]) + ([v[-1]] if (len(v) - 1) % step else [])
            for x in v:
                walk(x)

    walk(value)
    return out


def first_difference(module, reference) -> str:
    """Where syntax tree ``module`` first differs from ``reference`` (for an error row)."""
    if type(module) is not type(reference):
        return f"a {type(module).__name__} for a {type(reference).__name__}"
    for field in ("imports", "components", "systems"):
        mine, theirs = getattr(module, field), getattr(reference, field)
        for i, (a, b) in enumerate(zip(mine, theirs)):
            if a != b:
                return f"{field}[{i}]: {a!r:.300} for {b!r:.300}"
        if len(mine) != len(theirs):
            return f"{len(mine)} {field} for {len(theirs)}"
    return "the module's own fields"


ENGINES = {"verify": VerifyEngine, "lark-transformer": LarkTransformerEngine,
           "lark-standalone": LarkStandaloneEngine, "lark-tree": LarkTreeEngine}
