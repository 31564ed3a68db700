"""Hypothesis strategies for random *syntactically* valid modules of the verify language.

The trees say nothing sensible about timing (names need not resolve, bounds need not be ordered); they
are what the grammar accepts, for properties of the parser and the formatter. Examples stay small.
"""
from __future__ import annotations

import re
from fractions import Fraction

from hypothesis import strategies as st

from verify import syntax as s
from verify.parse import grammar_text

MODULE_PATH = "<text>"


def _grammar_keywords() -> frozenset[str]:
    """Every word the grammar spells as a string literal (comments in the grammar skipped)."""
    code = "\n".join(line.split("//", 1)[0] for line in grammar_text().splitlines())
    return frozenset(re.findall(r'"([A-Za-z_][A-Za-z0-9_]*)"', code))


KEYWORDS = _grammar_keywords()
UNITS = tuple(s.TIME_UNITS) + tuple(s.FREQUENCY_UNITS)
RESERVED = KEYWORDS | frozenset(UNITS)

#: plain names, and names that start like a keyword or a unit (the lexer must not split them)
NAME_POOL = tuple(sorted(
    ({"a", "b", "x", "_", "_x9", "A", "Cam", "lidar", "scan", "map_2", "cpu0", "plan", "msg", "sec"}
     | {word + suffix for word in KEYWORDS | set(UNITS) for suffix in ("_", "1", "s")})
    - RESERVED
))
names = st.sampled_from(NAME_POOL).map(s.Name)

#: exact values: integers, terminating decimals and non-terminating rationals such as 100/3
fractions = st.one_of(
    st.integers(0, 10**6).map(Fraction),
    st.builds(Fraction, st.integers(0, 10**5), st.sampled_from([2, 3, 4, 5, 6, 7, 8, 9, 10, 16, 25, 1000])),
)
numbers = fractions.map(s.Number)
quantities = st.builds(s.Quantity, fractions, st.sampled_from(UNITS))


def _optional(strategy):
    return st.none() | strategy


def _tuples(strategy, min_size: int = 0, max_size: int = 2):
    return st.lists(strategy, min_size=min_size, max_size=max_size).map(tuple)


# ------------------------------------------------------------------ components

tolerances = st.one_of(
    st.just(s.Tolerance("ok")),
    st.just(s.Tolerance("forbidden")),
    st.builds(s.Tolerance, st.just("max"), numbers),
)
reads = st.builds(s.Read, names, st.booleans(), _optional(tolerances), _optional(tolerances))
constraints = st.one_of(
    st.builds(s.ActivationConstraint, quantities, quantities, st.booleans()),
    st.builds(lambda q, ch: s.ActivationConstraint(q, q, ch), quantities, st.booleans()),
    st.builds(s.ActivationConstraint, quantities, st.none(), st.booleans()),
    st.builds(s.ActivationConstraint, st.none(), quantities, st.booleans()),
)
tasks = st.builds(
    s.Task,
    names,
    st.sampled_from(["preemptive", "cooperative"]),
    _tuples(reads),
    _tuples(names),
    _optional(quantities),
    _optional(quantities),
    _optional(constraints),
)
compound_constraints = _optional(constraints)
compounds = st.builds(
    s.CompoundPort, names, st.sampled_from(["and", "or"]), _tuples(names, 2, 3), compound_constraints
)
components = st.builds(
    s.Component,
    names,
    _tuples(st.builds(s.InPort, names, names), max_size=2),
    _tuples(st.builds(s.OutPort, names, names), max_size=2),
    _tuples(compounds, max_size=2),
    _tuples(tasks, max_size=3),
)

# ------------------------------------------------------------------ activations

period_holes = st.one_of(
    st.just(s.PeriodHole()),
    st.builds(s.PeriodHole, quantities, quantities, _optional(quantities)),
)
prescaler_holes = st.one_of(st.just(s.PrescalerHole()), st.builds(s.PrescalerHole, numbers, numbers))
activations = st.one_of(
    st.builds(s.Timer, quantities | period_holes, _optional(quantities)),
    st.builds(s.Trigger, names),
    st.builds(s.Trigger, names, numbers | prescaler_holes),
    st.builds(s.Sporadic, quantities, quantities),
    st.just(s.UnknownActivation()),
)

# ------------------------------------------------------------------ systems

bindings = st.builds(
    s.TaskBinding,
    names,
    _optional(numbers),
    _optional(names),
    _tuples(activations, max_size=2),
    _optional(quantities),
    _optional(quantities),
)
instances = st.builds(s.Instance, names, names, _optional(names), _tuples(bindings))
port_refs = st.builds(s.PortRef, names, names)
delays = st.one_of(
    st.just((None, None)),
    quantities.map(lambda q: (q, q)),
    st.tuples(quantities, quantities),
)
connections = st.builds(lambda src, dst, d: s.Connection(src, dst, *d), port_refs, port_refs, delays)
specs = st.builds(s.Spec, st.sampled_from(["reaction_time", "data_age", "jitter"]), quantities)
chains = st.builds(s.Chain, names, _tuples(port_refs, 1, 3), _tuples(specs))
systems = st.builds(
    s.System,
    names,
    _tuples(st.builds(s.Core, names, _optional(names)), max_size=2),
    _tuples(instances),
    _tuples(connections),
    _tuples(chains, max_size=2),
)

import_paths = st.sampled_from(["lib.vfy", "a//b.vfy", "dir/x.vfy", "/*.vfy", "_"])
modules = st.builds(
    s.Module,
    st.just(MODULE_PATH),
    _tuples(st.builds(s.Import, import_paths), max_size=2),
    _tuples(components, max_size=3),
    _tuples(systems, max_size=2),
)
