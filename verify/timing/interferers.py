"""hp(i) of every task of a core without a copy per task: ``TaskResponse.interferers`` as a view.

The tasks of a core that may delay a task i are those of i's priority or higher, in declaration order
(then, after them, i's remote cooperative siblings). A tuple of them per task holds n²/2 names for n
tasks on one core (100,000 tasks: 5·10⁹). ``CoreOrder`` holds a core's task ids and priority levels once;
``Interferers`` is one task's view of it: the tasks at its level or above but itself, plus a few extra
names. It is a ``Sequence[str]`` equal to the tuple it stands for; iterating it takes O(log n) per
element (``CoreOrder.next_at``: a tree of the least level below each node), so the first few names
(a diagnostic's) cost O(log n) each, however far apart they are on the core.
"""
from __future__ import annotations

from bisect import bisect_right
from collections.abc import Iterator, Sequence
from itertools import islice
from typing import overload


class CoreOrder:
    """The tasks of one core in declaration order and their priority levels (0 the highest), shared by
    every ``Interferers`` of the core."""

    __slots__ = ("ids", "levels", "_size", "_tree", "_sorted_levels")

    def __init__(self, ids: Sequence[str], levels: Sequence[int]):
        self.ids = tuple(ids)
        self.levels = tuple(levels)
        size = 1
        while size < len(self.ids):
            size *= 2
        top = max(self.levels, default=0) + 1  # (beyond every level: padding)
        tree = [top] * (2 * size)
        tree[size:size + len(self.levels)] = self.levels
        for k in range(size - 1, 0, -1):
            tree[k] = min(tree[2 * k], tree[2 * k + 1])
        self._size, self._tree = size, tree
        self._sorted_levels = sorted(self.levels)

    def count_at(self, level: int) -> int:
        """How many tasks of the core are at ``level`` or above."""
        return bisect_right(self._sorted_levels, level)

    def next_at(self, start: int, level: int) -> int | None:
        """The first position from ``start`` on whose task is at ``level`` or above, or None."""
        if start >= len(self.ids):
            return None
        tree, size = self._tree, self._size
        k = start + size
        while tree[k] > level:  # up to the next subtree to the right that holds one
            while k & 1:  # (a right child: its parent's next sibling is next)
                k >>= 1
                if k == 0:
                    return None
            k += 1
        while k < size:  # down to its first such leaf
            k = 2 * k if tree[2 * k] <= level else 2 * k + 1
        return k - size


class Interferers(Sequence[str]):
    """The ids of the tasks of ``order`` at ``level`` or above but ``own`` (declaration order), then
    ``extra``: equal to (and hashing as) the tuple of them."""

    __slots__ = ("order", "level", "own", "extra", "_length")

    def __init__(self, order: CoreOrder, level: int, own: str, extra: tuple[str, ...] = ()):
        self.order, self.level, self.own, self.extra = order, level, own, extra
        self._length = order.count_at(level) - 1 + len(extra)  # (``own`` is at ``level``)

    def __len__(self) -> int:
        return self._length

    def __iter__(self) -> Iterator[str]:
        order, level, own = self.order, self.level, self.own
        at = order.next_at(0, level)
        while at is not None:
            if order.ids[at] != own:
                yield order.ids[at]
            at = order.next_at(at + 1, level)
        yield from self.extra

    @overload
    def __getitem__(self, index: int) -> str: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[str, ...]: ...

    def __getitem__(self, index: int | slice) -> str | tuple[str, ...]:
        if isinstance(index, slice):
            start, stop, step = index.indices(self._length)
            if step == 1:
                return tuple(islice(self, start, max(start, stop)))
            return tuple(self)[index]
        if index < 0:
            index += self._length
        if not 0 <= index < self._length:
            raise IndexError("interferer index out of range")
        return next(islice(self, index, None))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Interferers) and (other.order, other.level, other.own, other.extra) == (
                self.order, self.level, self.own, self.extra):
            return True
        if not isinstance(other, Sequence) or isinstance(other, str) or len(other) != self._length:
            return False
        return all(a == b for a, b in zip(self, other))

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return repr(tuple(self))
