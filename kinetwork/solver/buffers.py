"""Functions of (t, x, p) called through ``Function.buffer`` straight from and into arrays
made once, their parameters written in place: what locating events calls thousands of times
a run (a plain call costs ~16 us of conversions, a ``pointwise`` call makes its arrays and
looks its map up again each time: 0.3 ms).
"""

import numpy as np

from ..equations.pointwise import pointwise

#: points of one map at most (its arrays are made once and kept), and maps kept per Function
MOST = 4096
SIZES = 16


class Call:
    """A Function of (t, x, p) as a fast callable of (t, x) at one point; ``p`` is an array
    written in place when the values it holds change."""

    def __init__(self, f, p):
        self.f = f
        self.buffer, self.trigger = f.buffer()
        self.t, self.x = np.zeros(1), np.zeros(f.size1_in(1))
        self.p = np.array(p, dtype=float)
        self.out = np.zeros(f.numel_out(0))            # column-major, flat
        # CasADi keeps raw pointers: the arrays live as long as this object
        for i, arr in enumerate((self.t, self.x, self.p)):
            self.buffer.set_arg(i, memoryview(arr))
        self.buffer.set_res(0, memoryview(self.out))

    def __call__(self, t, x):
        self.t[0] = t
        self.x[:] = x
        self.trigger()
        return self.out.copy()


class Points:
    """A Function of (t, x, p) at n points at once (its first output, a row a point,
    flattened column-major): one map, made once, the parameters shared."""

    def __init__(self, f, n):
        self.f, self.n = f, n
        self.buffer, self.trigger = f.map(f"{f.name()}_at_{n}", "serial", n, [2], []).buffer()
        self.t, self.x = np.zeros(n), np.zeros((n, f.size1_in(1)))
        self.p = np.zeros(f.size1_in(2))
        self.out = np.zeros((n, f.numel_out(0)))
        for i, arr in enumerate((self.t, self.x, self.p)):
            self.buffer.set_arg(i, memoryview(arr))
        self.buffer.set_res(0, memoryview(self.out))

    def __call__(self, T, X, p):
        self.t[:], self.x[:], self.p[:] = T, X, p
        self.trigger()
        return self.out.copy()


class PointsBySize:
    """``Points`` of one Function, one per number of points asked for (a few sizes a run: at
    most SIZES kept, the oldest dropped); over MOST points, ``pointwise``'s blocks."""

    def __init__(self):
        self._made = {}

    def __call__(self, f, T, X, p):
        if len(T) > MOST:
            return pointwise(f, np.asarray(T, dtype=float)[:, None], X, p)[0]
        points = self._made.get(len(T))
        if points is None or points.f is not f:
            if len(self._made) >= SIZES:
                self._made.pop(next(iter(self._made)))
            points = self._made[len(T)] = Points(f, len(T))
        return points(T, X, p)
