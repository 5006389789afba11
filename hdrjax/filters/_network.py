"""Comparator networks built symbolically, pruned, then emitted as elementwise min/max.

A :class:`Network` holds wires (inputs and ``min``/``max`` nodes, hash-consed so a
comparison is never built twice); merging sorted lists uses Batcher's odd–even merge, which
is valid for lists of any lengths (Knuth, TAOCP vol. 3, §5.3.4, ex. 3). :meth:`select`
finds one order statistic by merging sorted runs and *forgetting* elements that can no
longer reach the wanted rank (an element at index ``i`` of a sorted run of length ``L``
among ``n`` values has global rank between ``i`` and ``n - L + i``): the network is pruned
before anything is emitted, and only the cone of the requested outputs is traced.

Everything here is plain Python on the host, run once per filter size at trace time.
"""

from collections.abc import Callable, Hashable, Sequence
from typing import Any

NEG_INF = -1
"""Wire that is below every value (padding for the odd–even merge)."""
POS_INF = -2
"""Wire that is above every value."""


class Network:
    """A comparator network over symbolic wires (ints); see the module docstring."""

    def __init__(self) -> None:
        self._nodes: list[tuple[str, Any, Any]] = []
        self._memo: dict[tuple[str, Any, Any], int] = {}

    def leaf(self, key: Hashable) -> int:
        """The input wire named ``key`` (e.g. a window offset)."""
        node = ("in", key, None)
        if node not in self._memo:
            self._memo[node] = len(self._nodes)
            self._nodes.append(node)
        return self._memo[node]

    def _op(self, op: str, a: int, b: int) -> int:
        if a == b:
            return a
        if a > b:
            a, b = b, a
        # absorption: min(a, max(a, b)) = a and max(a, min(a, b)) = a
        for x, y in ((a, b), (b, a)):
            kind, p, q = self._nodes[x]
            if kind not in ("in", op) and y in (p, q):
                return y
        node = (op, a, b)
        if node not in self._memo:
            self._memo[node] = len(self._nodes)
            self._nodes.append(node)
        return self._memo[node]

    def minimum(self, a: int, b: int) -> int:
        if NEG_INF in (a, b):
            return NEG_INF
        if a == POS_INF:
            return b
        if b == POS_INF:
            return a
        return self._op("min", a, b)

    def maximum(self, a: int, b: int) -> int:
        if POS_INF in (a, b):
            return POS_INF
        if a == NEG_INF:
            return b
        if b == NEG_INF:
            return a
        return self._op("max", a, b)

    def exchange(self, a: int, b: int) -> tuple[int, int]:
        """A comparator: ``(min(a, b), max(a, b))``."""
        return self.minimum(a, b), self.maximum(a, b)

    def merge(self, a: Sequence[int], b: Sequence[int]) -> list[int]:
        """Batcher's odd–even merge of two sorted lists (any lengths)."""
        a, b = list(a), list(b)
        if not a:
            return b
        if not b:
            return a
        if len(a) == 1 and len(b) == 1:
            return list(self.exchange(a[0], b[0]))
        even = self.merge(a[0::2], b[0::2])
        odd = self.merge(a[1::2], b[1::2])
        out = [even[0]]
        i = 0
        while i < len(odd) and i + 1 < len(even):
            out.extend(self.exchange(odd[i], even[i + 1]))
            i += 1
        return out + odd[i:] + even[i + 1 :]

    def sort(self, xs: Sequence[int]) -> list[int]:
        """Odd–even merge sort."""
        xs = list(xs)
        if len(xs) <= 1:
            return xs
        h = len(xs) // 2
        return self.merge(self.sort(xs[:h]), self.sort(xs[h:]))

    def select_range(self, runs: Sequence[Sequence[int]], lo: int, hi: int) -> list[int]:
        """Order statistics ``lo..hi`` (0-based, inclusive) of the union of sorted ``runs``."""
        runs, lo, hi = _prune([list(r) for r in runs], lo, hi)
        while len(runs) > 1:
            runs.sort(key=len)  # merge the two shortest runs first
            runs = [self.merge(runs[0], runs[1]), *runs[2:]]
            runs, lo, hi = _prune(runs, lo, hi)
        return runs[0][lo : hi + 1]

    def select(self, runs: Sequence[Sequence[int]], rank: int) -> int:
        """Order statistic ``rank`` (0-based) of the union of sorted ``runs``."""
        return self.select_range(runs, rank, rank)[0]

    def size(self, outputs: Sequence[int]) -> int:
        """Number of min/max operations in the cone of ``outputs``."""
        seen: set[int] = set()
        stack = [o for o in outputs if o >= 0]
        while stack:
            n = stack.pop()
            if n in seen:
                continue
            seen.add(n)
            kind, a, b = self._nodes[n]
            if kind != "in":
                stack += [a, b]
        return sum(1 for n in seen if self._nodes[n][0] != "in")

    def leaves(self, outputs: Sequence[int]) -> list[Hashable]:
        """Keys of the inputs the cone of ``outputs`` reads."""
        seen: set[int] = set()
        keys = []
        stack = [o for o in outputs if o >= 0]
        while stack:
            n = stack.pop()
            if n in seen:
                continue
            seen.add(n)
            kind, a, b = self._nodes[n]
            if kind == "in":
                keys.append(a)
            else:
                stack += [a, b]
        return keys

    def emit(
        self,
        outputs: Sequence[int],
        inputs: Callable[[Hashable], Any],
        minimum: Callable[[Any, Any], Any],
        maximum: Callable[[Any, Any], Any],
    ) -> list[Any]:
        """Evaluate the cone of ``outputs``; ``inputs(key)`` gives each input's value."""
        if any(o < 0 for o in outputs):
            raise ValueError("an output wire is a constant (the network was over-pruned)")
        vals: dict[int, Any] = {}
        for o in outputs:
            stack = [o]
            while stack:
                n = stack[-1]
                if n in vals:
                    stack.pop()
                    continue
                kind, a, b = self._nodes[n]
                if kind == "in":
                    vals[n] = inputs(a)
                    stack.pop()
                    continue
                todo = [c for c in (a, b) if c not in vals]
                if todo:
                    stack += todo
                    continue
                vals[n] = (minimum if kind == "min" else maximum)(vals[a], vals[b])
                stack.pop()
        return [vals[o] for o in outputs]


def _prune(runs: list[list[int]], lo: int, hi: int) -> tuple[list[list[int]], int, int]:
    """Forget run elements whose possible global ranks miss ``[lo, hi]``."""
    changed = True
    while changed:
        changed = False
        runs = [r[: hi + 1] for r in runs]  # index > hi: at least hi + 1 values below
        n = sum(len(r) for r in runs)
        kept = []
        for r in runs:
            drop = lo - (n - len(r))  # index < drop: at most lo - 1 values below... all below lo
            if drop > 0:
                r = r[drop:]
                lo, hi, n = lo - drop, hi - drop, n - drop
                changed = True
            if r:
                kept.append(r)
        runs = kept
        changed = changed or any(len(r) > hi + 1 for r in runs)
    return runs, lo, hi
