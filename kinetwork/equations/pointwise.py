"""A compiled Function evaluated at many points at once: its map, made once per size, called
through ``Function.buffer`` straight from and into numpy arrays (no DM conversions).
"""

import functools

import numpy as np

#: points per call of ``pointwise``: a map over every point of a long run cost more to make
#: than to evaluate (1e6 points: 14 s to make, 19 s to call with its DM conversions, 8 s to
#: read back, against 0.3 s to evaluate). Making a map costs more than in proportion to its
#: points (its work arrays hold every point's): EngineV6's poses (``System.f_frames``) at
#: 1011 points took 60 ms of CPU the first time with maps of 4096 points, 15 ms with 256
#: (10 ms again either way); past 256 the calls' own cost is below a 20th of the points'
POINTS_PER_CALL = 256


@functools.lru_cache(maxsize=64)
def _mapped(f, n, shared):
    """``f`` mapped over ``n`` points, the inputs ``shared`` the same for all; made once per
    Function, size and sharing (making it costs ~0.5 ms)."""
    return f.map(f"{f.name()}_points", "serial", n, list(shared), [])


@functools.lru_cache(maxsize=64)
def mapped(f, n):
    """``f.map(n)``, made once per Function and size (making it costs ~0.5 ms): for callers
    that read the call's return status themselves (``solver.batch``)."""
    return f.map(n)


def pointwise(f, *args):
    """Each output of ``f`` at every point: one array (n_points, numel) per output, each
    row the output at that point flattened column-major.

    An argument is an array of one row per point (2-D: (n_points, nnz of the input)), or
    one value for all (1-D, its nnz). ``f`` runs over POINTS_PER_CALL points per call of
    its map, through ``Function.buffer`` straight from and into numpy arrays (no DM)."""
    rows = [np.ascontiguousarray(a, dtype=float) if np.ndim(a) == 2 else None for a in args]
    n = next(len(r) for r in rows if r is not None)
    shared = tuple(i for i, r in enumerate(rows) if r is None)
    fixed = [None if r is not None else np.ascontiguousarray(np.ravel(a), dtype=float)
             for r, a in zip(rows, args)]
    outs = [np.zeros((n, f.nnz_out(j))) for j in range(f.n_out())]
    size = min(n, POINTS_PER_CALL)
    if size:
        F = _mapped(f, size, shared)
        buf, trigger = F.buffer()
        for i, value in enumerate(fixed):
            if value is not None:
                buf.set_arg(i, memoryview(value))
        for k in range(0, n, size):
            m = min(size, n - k)
            # the last call's missing points repeat its last one; CasADi keeps raw
            # pointers: the arrays are kept alive (``blocks``, ``out``) until it has run
            blocks = [None if r is None else r[k:k + size] if m == size else
                      np.concatenate([r[k:], np.repeat(r[-1:], size - m, axis=0)])
                      for r in rows]
            for i, block in enumerate(blocks):
                if block is not None:
                    buf.set_arg(i, memoryview(block))
            out = [o[k:k + size] if m == size else np.zeros((size, o.shape[1]))
                   for o in outs]
            for j, o in enumerate(out):
                buf.set_res(j, memoryview(o))
            trigger()
            if m < size:
                for o, partial in zip(outs, out):
                    o[k:] = partial[:m]
    return [_dense(f.sparsity_out(j), o) for j, o in enumerate(outs)]


def _dense(sparsity, values):
    """Rows of nonzeros of ``sparsity`` as rows of its dense, column-major entries."""
    if sparsity.is_dense():
        return values
    rows, cols = sparsity.get_triplet()
    out = np.zeros((len(values), sparsity.numel()))
    out[:, np.asarray(rows) + sparsity.size1() * np.asarray(cols)] = values
    return out
