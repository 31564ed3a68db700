"""Fixed inputs and a full structural dump for the performance-equivalence tests.

``tests/test_perf_equivalence.py`` compares what the front end (typed tree with every span, semantic
model, diagnostics) and the timing analysis (every field of the result) produce on these inputs with
digests recorded from the implementation *before* the performance work (golden files in
``tests/golden/perf``). ``dump`` walks dataclasses through all their fields, including the spans and
other fields that take no part in ``repr`` or equality, so a changed column is caught too.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import random
import re
from collections.abc import Sequence
from enum import Enum
from fractions import Fraction

from .conftest import EXAMPLES


def dump(value):
    """A JSON-ready structure of ``value`` with every dataclass field (spans included)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [type(value).__name__] + [[f.name, dump(getattr(value, f.name))] for f in dataclasses.fields(value)]
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, (tuple, list, Sequence)) and not isinstance(value, str):  # (a view: ``timing.interferers``)
        return [dump(v) for v in value]
    if isinstance(value, dict):
        return [["dict"]] + [[dump(k), dump(v)] for k, v in value.items()]
    if isinstance(value, (set, frozenset)):
        return sorted((dump(v) for v in value), key=repr)
    if isinstance(value, Fraction):
        return f"F{value.numerator}/{value.denominator}"
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):  # pragma: no cover - the analysis is exact
        return repr(value)
    raise TypeError(f"cannot dump {type(value).__name__}")


def digest(value, root: str | None = None) -> str:
    """SHA-256 of the dump; with ``root``, that path prefix is written ``<root>`` so a digest does not
    depend on where the repository is checked out."""
    text = json.dumps(dump(value), separators=(",", ":"))
    if root is not None:
        text = text.replace(json.dumps(root)[1:-1], "<root>")
    return hashlib.sha256(text.encode()).hexdigest()


# ------------------------------------------------------------------ systems with cooperative siblings

PERIODS_MS = (5, 10, 20, 25, 40, 50, 100)


def _ms(value: Fraction) -> str:
    return f"{value.numerator}/{value.denominator} ms" if value.denominator != 1 else f"{value.numerator} ms"


def coop_system(seed: int, n: int, load: int = 2) -> str:
    """A random valid system in DSL text with what the benchmark generator never writes: cooperative
    siblings (local and remote), sporadic sources, AND/OR compound triggers, prescalers, equal
    priorities, user WCRT bounds and deadlines, connection delays and chains. ``load`` scales the
    execution times (higher: overloaded cores, unbounded responses, E312)."""
    rng = random.Random(seed)
    cores = rng.randint(1, 3)
    components, bindings, connections, chains = [], [], [], []
    edges: dict[int, list[int]] = {}
    for i in range(n):
        reads, ins, extra, act = [], [], [], None
        if i == 0 or rng.random() < 0.5:
            period = rng.choice(PERIODS_MS)
            if rng.randint(0, 3) == 0:
                act = f"sporadic {period} ms .. {_ms(Fraction(period * rng.randint(4, 8), 4))}"
            else:
                act = f"timer {period} ms" + (f" phase {rng.randint(0, period - 1)} ms" if rng.random() < 0.3 else "")
        else:
            mode = rng.choice(["single", "single", "and", "or"])
            k = rng.choice([1, 1, 2, 3])
            members = ["a"] if mode == "single" else ["a", "b"]
            for m in members:
                w = rng.randint(0, i - 1)
                ins.append(m)
                reads.append(m)
                connections.append((w, i, m))
                edges.setdefault(w, []).append(i)
            port = "a" if mode == "single" else "ab"
            if mode != "single":
                extra.append(f"  in ab = a {'&' if mode == 'and' else '|'} b")
            act = f"trigger {port}" + (f" every {k}" if k > 1 else "")
        if i > 0 and rng.random() < 0.5:
            w = rng.randint(0, i - 1)
            ins.append("r")
            reads.append("r")
            connections.append((w, i, "r"))
            edges.setdefault(w, []).append(i)
        # utilisation share about load/4 of a core per task and core... spread over all tasks
        share = Fraction(rng.randint(1, 8), 8) * Fraction(load * cores, 6 * n)
        period_ms = int(act.split()[1]) if act.split()[1].isdigit() else 20
        wcet = max(Fraction(1, 8), (share * period_ms).limit_denominator(16))
        bcet = wcet * Fraction(rng.randint(0, 4), 4)
        coop = rng.randint(0, 2) == 0
        sibling = coop and rng.random() < 0.7
        lines = [f"component C{i} {{"] + [f"  in {p} : T" for p in ins] + ["  out o : T"] + extra
        lines += [f"  task T{'' if not coop else ' cooperative'} {{"] + [f"    reads {r}" for r in reads]
        lines += ["    produces o", f"    bcet {_ms(bcet)}", f"    wcet {_ms(wcet)}", "  }"]
        if sibling:
            lines += ["  task S cooperative {", f"    wcet {_ms(wcet / 2)}", "  }"]
        lines.append("}")
        components.append("\n".join(lines))
        core = rng.randint(0, cores - 1)
        extra_clause = ""
        if rng.random() < 0.1:
            extra_clause = f" wcrt {_ms(wcet * 3)}"
        elif rng.random() < 0.15:
            extra_clause = f" deadline {rng.choice(PERIODS_MS)} ms"
        body = [f"    task T priority {rng.randint(1, 6)} {act}{extra_clause}"]
        if sibling:
            sib_core = rng.randint(0, cores - 1)
            body.append(f"    task S priority {rng.randint(1, 6)} on c{sib_core} timer {rng.choice(PERIODS_MS)} ms")
        bindings.append(f"  instance i{i} : C{i} on c{core} {{\n" + "\n".join(body) + "\n  }")
    conn_lines = []
    for w, r, port in connections:
        dmin = rng.choice([0, 0, 1, 2])
        dmax = dmin + rng.choice([0, 0, 1, 3])
        delay = "" if dmax == 0 else f" delay {dmin} ms .. {dmax} ms"
        conn_lines.append(f"  connect i{w}.o -> i{r}.{port}{delay}")
    for c in range(rng.randint(1, 4)):
        path = [rng.randint(0, n - 1)]
        while len(path) < 6 and path[-1] in edges and rng.randint(0, 4) > 0:
            nxt = rng.choice(sorted(set(edges[path[-1]])))
            if nxt in path:
                break
            path.append(nxt)
        specs = ""
        if rng.random() < 0.5:
            specs = f" {{ reaction_time <= {rng.randint(20, 400)} ms data_age <= {rng.randint(20, 400)} ms }}"
        chains.append(f"  chain ch{c}: " + " -> ".join(f"i{t}.o" for t in path) + specs)
    system = ["system S {"] + [f"  core c{c}" for c in range(cores)] + bindings + conn_lines + chains + ["}"]
    return "\n\n".join(components) + "\n\n" + "\n".join(system) + "\n"


def mutate(text: str, rng: random.Random, semantic: bool = False) -> str:
    """A few random edits (those of tests/test_robustness.py and more): syntax errors; with
    ``semantic``, one or two words swapped for others of the text (mostly E1xx–E3xx)."""
    chars = list(text)
    for _ in range(rng.randint(1, 2) if semantic else rng.randint(1, 6)):
        op = 4 if semantic else rng.randrange(6)
        pos = rng.randrange(len(chars) + 1)
        if op == 0 and chars:
            del chars[min(pos, len(chars) - 1)]
        elif op == 1:
            chars.insert(pos, rng.choice("{}:;.->?&|\"/*0123456789 \nabcHzms#é\t"))
        elif op == 2 and chars:
            i = rng.randrange(len(chars))
            j = rng.randrange(len(chars))
            chars[i], chars[j] = chars[j], chars[i]
        elif op == 3:
            word = rng.choice(["task", "in", "on", "timer", "component", "system", "ms", "Hz", "/*", "*/",
                               "//", "\"x\"", "1/0", "..", "->", "0000000000000000000000000000000000000000001"])
            chars.insert(pos, f" {word} ")
        elif op == 4:  # one word or number for another of the text: mostly semantic errors
            words = re.findall(r"[A-Za-z_][A-Za-z0-9_]*|[0-9]+", "".join(chars))
            if words:
                old, new = rng.choice(words), rng.choice(words)
                text_now = "".join(chars)
                at = [m.start() for m in re.finditer(rf"\b{re.escape(old)}\b", text_now)]
                if at:
                    k = rng.choice(at)
                    chars = list(text_now[:k] + new + text_now[k + len(old):])
        else:
            a = rng.randrange(len(chars) + 1)
            b = min(len(chars), a + rng.randint(1, 30))
            del chars[a:b]
    return "".join(chars)


# ------------------------------------------------------------------ the cases


def _generated(n: int, seed: int, **options) -> str:
    from benchmarks.generate import generate_system

    return generate_system(n, seed, **options)


def analysis_cases() -> dict[str, str]:
    """name -> DSL text of a system that loads cleanly (analysed in both data-age variants)."""
    cases = {"navigation": "navigation"}  # loaded from disk (imports)
    for n, seed in ((20, 1), (20, 2), (60, 1), (60, 3), (150, 1), (150, 2), (250, 4)):
        cases[f"waters-{n}-s{seed}"] = _generated(n, seed)
    cases["waters-80-s5-1core"] = _generated(80, 5, cores=1)
    cases["waters-120-s6-2cores-chains"] = _generated(120, 6, cores=2, chains=40)
    for seed in range(1, 31):
        n = 4 + seed % 13 * 3
        cases[f"coop-{seed}"] = coop_system(seed, n, load=1 + seed % 4)
    # lightly loaded: mostly bounded, with cooperative blocking and multi-job busy windows
    for seed in (31, 32, 36, 37, 38, 41, 51, 54, 57, 58, 62, 64, 67, 69, 74, 79, 93, 97, 104, 105):
        cases[f"coop-light-{seed}"] = coop_system(seed, 6 + seed % 9 * 4, load=1)
    return cases


def load_cases() -> dict[str, str]:
    """name -> DSL text for the front end (valid, with holes, infeasible, and broken by mutation)."""
    nav = (EXAMPLES / "navigation" / "navigation.vfy").read_text()
    comps = (EXAMPLES / "navigation" / "components.vfy").read_text()
    cases = {"navigation.vfy": nav, "components.vfy": comps,
             "holes.vfy": (EXAMPLES / "navigation" / "navigation-holes.vfy").read_text(),
             "conflict.vfy": (EXAMPLES / "navigation" / "navigation-conflict.vfy").read_text(),
             "waters-100-holes": _generated(100, 7, hole_share=Fraction(1, 4)),
             "waters-100-infeasible": _generated(100, 8, infeasible=True),
             "waters-300": _generated(300, 9)}
    for seed in range(1, 11):
        cases[f"coop-{seed}"] = coop_system(seed, 8)
    sources = [nav, comps, cases["coop-1"], comps + "\n" + cases["coop-2"], _generated(10, 3)]
    rng = random.Random(2026)
    for k in range(400):
        cases[f"mutant-{k}"] = mutate(sources[k % len(sources)], rng, semantic=k % 3 == 0)
    return cases
