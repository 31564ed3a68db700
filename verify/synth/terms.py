"""Linear integer terms and conditions for the Z3 encoding (``verify.synth.encode``): Python ints and bools
where a value is known without Z3, Z3 expressions once a variable is involved, built through Z3's C API."""
from __future__ import annotations

from typing import TypeAlias
from collections.abc import Callable

import z3

#: a linear term: a Python int, or a Z3 integer expression once a variable is involved
Term: TypeAlias = "int | z3.ArithRef"
#: a constraint: a Python bool when decided without Z3, else a Z3 Boolean expression
Cond: TypeAlias = "bool | z3.BoolRef"


class Terms:
    """Linear terms in one context; Python ints are folded and only lifted into Z3 when mixed.

    Terms are built through Z3's C API directly: the same terms z3py's operators build (binary
    ``+`` nested to the left, ``k * x``, ``If``), without its per-operation coercion, which made up
    half the time of building a 1,000-task encoding."""

    def __init__(self, ctx: z3.Context):
        self.ctx = ctx
        self._ref = ctx.ref()
        self._int = z3.IntSort(ctx)  # (kept alive: its AST is used for every numeral)

    def _num(self, x: int) -> z3.IntNumRef:  # (as z3.IntVal: operators dispatch on the subclass)
        return z3.IntNumRef(z3.Z3_mk_numeral(self._ref, str(x), self._int.ast), self.ctx)

    def _bin(self, make: Callable[..., z3.Ast], a: z3.ExprRef, b: z3.ExprRef) -> z3.Ast:
        args = (z3.Ast * 2)(a.ast, b.ast)
        return make(self._ref, 2, args)

    def _rel(self, make: Callable[..., z3.Ast], reflected: Callable[..., z3.Ast], a: Term, b: Term) -> z3.BoolRef:
        """``a OP b`` as z3py's operator builds it: Python tries the reflected operator of the right
        operand first when its class is a subclass of the left's (a numeral on the right)."""
        x, y = self.lift(a), self.lift(b)
        if type(y) is not type(x) and isinstance(y, type(x)):
            return z3.BoolRef(reflected(self._ref, y.ast, x.ast), self.ctx)
        return z3.BoolRef(make(self._ref, x.ast, y.ast), self.ctx)

    def implies(self, pre: list[z3.BoolRef], then: z3.BoolRef) -> z3.BoolRef:
        """``Implies(pre[0], then)``, or ``Implies(And(*pre), then)`` for several, as z3py builds them."""
        if len(pre) == 1:
            left = pre[0].ast
        else:
            left = z3.Z3_mk_and(self._ref, len(pre), (z3.Ast * len(pre))(*(x.ast for x in pre)))
        return z3.BoolRef(z3.Z3_mk_implies(self._ref, left, then.ast), self.ctx)

    def any_of(self, conds: list[z3.BoolRef]) -> z3.BoolRef:
        """``Or(*conds)`` (two or more), as z3py builds it."""
        args = (z3.Ast * len(conds))(*(c.ast for c in conds))
        return z3.BoolRef(z3.Z3_mk_or(self._ref, len(conds), args), self.ctx)

    def at_least(self, x: z3.ArithRef, k: int) -> z3.BoolRef:
        """``x >= k`` for a Python int ``k``, as z3py builds it."""
        return z3.BoolRef(z3.Z3_mk_ge(self._ref, x.ast, self._num(k).ast), self.ctx)

    def lift(self, x: Term) -> z3.ArithRef:
        return self._num(x) if isinstance(x, int) else x

    def add(self, *xs: Term) -> Term:
        const = sum(x for x in xs if isinstance(x, int))
        rest = [x for x in xs if not isinstance(x, int)]
        if not rest:
            return const
        total = rest[0]
        for x in rest[1:]:
            total = z3.ArithRef(self._bin(z3.Z3_mk_add, total, x), self.ctx)
        return z3.ArithRef(self._bin(z3.Z3_mk_add, total, self._num(const)), self.ctx) if const else total

    def mul(self, k: int, x: Term) -> Term:
        if isinstance(x, int):
            return k * x
        return x if k == 1 else z3.ArithRef(self._bin(z3.Z3_mk_mul, self._num(k), x), self.ctx)

    def _ite(self, cond: z3.BoolRef, a: Term, b: Term) -> z3.ArithRef:
        x, y = self.lift(a), self.lift(b)
        return z3.ArithRef(z3.Z3_mk_ite(self._ref, cond.ast, x.ast, y.ast), self.ctx)

    def max(self, a: Term, b: Term) -> Term:
        if isinstance(a, int) and isinstance(b, int):
            return max(a, b)
        return self._ite(self._rel(z3.Z3_mk_ge, z3.Z3_mk_le, a, b), a, b)

    def min(self, a: Term, b: Term) -> Term:
        if isinstance(a, int) and isinstance(b, int):
            return min(a, b)
        return self._ite(self._rel(z3.Z3_mk_le, z3.Z3_mk_ge, a, b), a, b)

    def ite(self, cond: Cond, a: Term, b: Term) -> Term:
        if isinstance(cond, bool):
            return a if cond else b
        return self._ite(cond, a, b)

    def le(self, a: Term, b: Term) -> Cond:
        if isinstance(a, int) and isinstance(b, int):
            return a <= b
        return self._rel(z3.Z3_mk_le, z3.Z3_mk_ge, a, b)

    def ge(self, a: Term, b: Term) -> Cond:
        if isinstance(a, int) and isinstance(b, int):
            return a >= b
        return self._rel(z3.Z3_mk_ge, z3.Z3_mk_le, a, b)

    def eq(self, a: Term, b: Term) -> Cond:
        if isinstance(a, int) and isinstance(b, int):
            return a == b
        return self._rel(z3.Z3_mk_eq, z3.Z3_mk_eq, a, b)


def conjunction(conds: list[Cond]) -> Cond:
    """The conjunction of ``conds``, decided without Z3 where it can be."""
    if any(c is False for c in conds):
        return False
    rest = [c for c in conds if c is not True]
    return True if not rest else rest[0] if len(rest) == 1 else z3.And(*rest)


def disjunction(conds: list[Cond]) -> Cond:
    """The disjunction of ``conds``, decided without Z3 where it can be."""
    if any(c is True for c in conds):
        return True
    rest = [c for c in conds if c is not False]
    return False if not rest else rest[0] if len(rest) == 1 else z3.Or(*rest)


def lt_pair(t: Terms, a: tuple[Term, Term], b: tuple[Term, Term]) -> Cond:
    """(a0, a1) < (b0, b1) lexicographically."""
    if all(isinstance(x, int) for x in (*a, *b)):
        return a < b
    a0, a1, b0, b1 = (t.lift(x) for x in (*a, *b))
    return z3.Or(a0 < b0, z3.And(a0 == b0, a1 < b1))
