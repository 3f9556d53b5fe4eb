"""Wires of a wiring diagram: routed orthogonally around the blocks (a shortest path with a
price on bends, crossings and overlaps, on a grid of lines beside the blocks), then spread
apart where they share a track, and the junction dots where a net branches."""

import bisect
import heapq
import itertools
import math

from .blocks import BEND, CLEAR, CROSS, STUB


class Router:
    """Orthogonal wires around the blocks: shortest paths on the grid of lines CLEAR beside
    every block's sides (and the middles between), with a price on bends, on crossing other
    wires and on running along them (none along a wire of the same net: they merge)."""

    def __init__(self, rects, stubs=()):
        self.blocks = [(x - 3, y - 3, x + w + 3, y + h + 3) for x, y, w, h in rects]
        self.xs = self._lines([x for bx, _, bw, _ in rects for x in (bx - CLEAR, bx + bw + CLEAR)],
                              [x for x, _ in stubs])
        self.ys = self._lines([y for _, by, _, bh in rects for y in (by - CLEAR, by + bh + CLEAR)],
                              [y for _, y in stubs])
        self.runs = ({}, {})          # (along y: [(x0, x1, net)], along x: [(y0, y1, net)])
        self._sorted = ([], [])       # the lines of runs[0] and runs[1], sorted
        self.cut = ({}, {})

    @staticmethod
    def _lines(values, stubs):
        """Grid lines: through every port's stub, beside every block unless a stub's line
        is within a few units (one track, so that wires of a net can merge on it), and
        down the middle of wide gaps."""
        lines = sorted(set(stubs))
        for v in sorted(set(values)):
            i = bisect.bisect_left(lines, v)
            if all(abs(v - lines[k]) >= 5 for k in (i - 1, i) if 0 <= k < len(lines)):
                lines.insert(i, v)
        middles = [(a + b) / 2 for a, b in zip(lines, lines[1:]) if b - a > 2 * CLEAR]
        return sorted(set(lines + middles))

    def _spans(self, axis, value):
        """The open intervals blocks cover along the line ``axis`` = ``value`` (axis 0: a
        horizontal line at y = value; 1: a vertical one at x = value)."""
        cache = self.cut[axis]
        if value not in cache:
            cache[value] = [(b[0], b[2]) if axis == 0 else (b[1], b[3]) for b in self.blocks
                            if (b[1] < value < b[3] if axis == 0 else b[0] < value < b[2])]
        return cache[value]

    def route(self, a, da, b, db, net):
        """Points of a wire from port ``a`` (leaving in direction ``da``) to port ``b``."""
        sa = (a[0] + da[0] * STUB, a[1] + da[1] * STUB)
        sb = (b[0] + db[0] * STUB, b[1] + db[1] * STUB)
        xs = sorted(set(self.xs) | {sa[0], sb[0]})
        ys = sorted(set(self.ys) | {sa[1], sb[1]})
        start = (xs.index(sa[0]), ys.index(sa[1]), 0 if da[1] == 0 else 1)
        goal, goal_o = (xs.index(sb[0]), ys.index(sb[1])), 0 if db[1] == 0 else 1
        found = self._search(xs, ys, start, goal, goal_o, net)
        if found is None:              # no way around (blocks overlap): a plain elbow
            middle = [(sb[0], sa[1])] if da[1] == 0 else [(sa[0], sb[1])]
            points = [a, sa, *middle, sb, b]
        else:
            points = [a, *found, b]
        points = simplify(points)
        self._remember(points, net)
        return points

    def _search(self, xs, ys, start, goal, goal_o, net):
        gx, gy = xs[goal[0]], ys[goal[1]]
        heap = [(0.0, 0.0, start)]
        best, back = {start: 0.0}, {}
        while heap:
            _, cost, state = heapq.heappop(heap)
            if cost > best.get(state, math.inf):
                continue
            ix, iy, o = state
            if (ix, iy) == goal:
                path = [(xs[ix], ys[iy])]
                while state in back:
                    state = back[state]
                    path.append((xs[state[0]], ys[state[1]]))
                return path[::-1]
            for jx, jy in ((ix - 1, iy), (ix + 1, iy), (ix, iy - 1), (ix, iy + 1)):
                if not (0 <= jx < len(xs) and 0 <= jy < len(ys)):
                    continue
                step = self._step(xs[ix], ys[iy], xs[jx], ys[jy], net)
                if step is None:
                    continue
                turn = 0 if jy == iy else 1
                extra = step + (BEND if turn != o else 0)
                if (jx, jy) == goal and turn != goal_o:
                    extra += BEND
                nxt = (jx, jy, turn)
                total = cost + extra
                if total < best.get(nxt, math.inf):
                    best[nxt], back[nxt] = total, state
                    guess = abs(xs[jx] - gx) + abs(ys[jy] - gy)
                    heapq.heappush(heap, (total + guess, total, nxt))
        return None

    def _step(self, x0, y0, x1, y1, net):
        """The price of the segment between two neighbouring grid points, None if a block
        is in the way."""
        axis = 0 if y0 == y1 else 1
        line, lo, hi = (y0, min(x0, x1), max(x0, x1)) if axis == 0 else \
            (x0, min(y0, y1), max(y0, y1))
        for s0, s1 in self._spans(axis, line):
            if s0 < hi and s1 > lo:
                return None
        length = hi - lo
        price = length
        for r0, r1, other in self.runs[axis].get(line, ()):
            shared = min(hi, r1) - max(lo, r0)
            if shared > 0:
                price += (-0.8 if other == net else 3.0) * shared
        crossing = self.runs[1 - axis]
        keys = self._sorted[1 - axis]
        for k in keys[bisect.bisect_right(keys, lo):bisect.bisect_left(keys, hi)]:
            if any(r0 < line < r1 and other != net for r0, r1, other in crossing[k]):
                price += CROSS
        return max(price, 0.05 * length)

    def _remember(self, points, net):
        for (x0, y0), (x1, y1) in zip(points, points[1:]):
            if y0 == y1:
                self.runs[0].setdefault(y0, []).append((min(x0, x1), max(x0, x1), net))
            else:
                self.runs[1].setdefault(x0, []).append((min(y0, y1), max(y0, y1), net))
        self._sorted = (sorted(self.runs[0]), sorted(self.runs[1]))


def simplify(points):
    """Drop repeated points and the middle of three in a line."""
    out = []
    for p in points:
        if out and p == out[-1]:
            continue
        if len(out) >= 2 and (out[-2][0] == out[-1][0] == p[0] or out[-2][1] == out[-1][1] == p[1]):
            out[-1] = p
        else:
            out.append(p)
    return out


def _inner(wires, axis):
    """The segments of wires that may move: [at, lo, hi, net, wire, index] of each inner
    segment along ``axis`` (1: vertical, at an x; 0: horizontal, at a y)."""
    out = []
    for w, (points, net) in enumerate(wires):
        for k in range(1, len(points) - 2):
            (x0, y0), (x1, y1) = points[k], points[k + 1]
            if (x0 == x1) == (axis == 1):
                out.append([x0, min(y0, y1), max(y0, y1), net, w, k] if axis == 1 else
                           [y0, min(x0, x1), max(x0, x1), net, w, k])
    return out


def _move(wires, blocks, axis, seg, new):
    """Move an inner segment to ``new`` unless a block is in the way there."""
    _, lo, hi, _, w, k = seg
    if any((b[0] < new < b[2] and b[1] < hi and b[3] > lo) if axis == 1 else
           (b[1] < new < b[3] and b[0] < hi and b[2] > lo) for b in blocks):
        return False
    points = wires[w][0]
    for j in (k, k + 1):
        x, y = points[j]
        points[j] = (new, y) if axis == 1 else (x, new)
    seg[0] = new
    return True


def spread(wires, blocks):
    """Tidy the tracks: segments of one net a few units apart that meet are put on one
    track; segments of different nets on one track are moved apart, in the order that
    crosses least. Only inner segments move (a wire's ends stay on its ports)."""
    for axis in (1, 0):
        segs = _inner(wires, axis)
        for i, seg in enumerate(segs):
            for other in segs[:i]:
                if other[3] == seg[3] and 0 < abs(other[0] - seg[0]) <= 4 and \
                        seg[1] <= other[2] and other[1] <= seg[2]:
                    if _move(wires, blocks, axis, seg, other[0]):
                        break
        groups = {}
        for seg in _inner(wires, axis):
            groups.setdefault(seg[0], []).append(seg)
        for at, segs in sorted(groups.items()):
            segs.sort(key=lambda s: (s[1], s[2], s[4]))
            clusters, reach = [], -math.inf
            for seg in segs:
                if clusters and seg[1] < reach:
                    clusters[-1].append(seg)
                    reach = max(reach, seg[2])
                else:
                    clusters.append([seg])
                    reach = seg[2]
            for cluster in clusters:
                nets = list(dict.fromkeys(s[3] for s in cluster))
                if len(nets) > 1:
                    _spread_cluster(wires, blocks, axis, at, cluster, nets)


def _spread_cluster(wires, blocks, axis, at, cluster, nets):
    # arms: where each net's segments turn off the track, and to which side
    arms = {net: [] for net in nets}
    spans = {net: [math.inf, -math.inf] for net in nets}
    for _, lo, hi, net, w, k in cluster:
        points = wires[w][0]
        spans[net] = [min(spans[net][0], lo), max(spans[net][1], hi)]
        for end, other in ((k, k - 1), (k + 1, k + 2)):
            p, q = points[end], points[other]
            along = p[1] if axis == 1 else p[0]
            away = q[0] - p[0] if axis == 1 else q[1] - p[1]
            arms[net].append((along, 1 if away > 0 else -1))

    def crossings(arrangement):
        total = 0
        for i, n in enumerate(arrangement):
            for m in arrangement[i + 1:]:           # n before m
                total += sum(1 for y, s in arms[n] if s > 0 and spans[m][0] < y < spans[m][1])
                total += sum(1 for y, s in arms[m] if s < 0 and spans[n][0] < y < spans[n][1])
        return total
    if len(nets) <= 6:
        arrangement = min(itertools.permutations(nets), key=crossings)
    else:
        arrangement = sorted(nets, key=lambda n: sum(spans[n]))
    for i, net in enumerate(arrangement):
        shift = (i - (len(arrangement) - 1) / 2) * 6
        if shift:
            for seg in cluster:
                if seg[3] == net:
                    _move(wires, blocks, axis, seg, at + shift)


def wire_junctions(wires):
    """Points where wires of one net branch: three or more directions meet."""
    dots = []
    nets = {}
    for points, net in wires:
        nets.setdefault(net, []).append(points)
    for net, paths in nets.items():
        if len(paths) < 2:
            continue
        segments = {tuple(sorted((p, q))) for path in paths for p, q in zip(path, path[1:])}
        for point in dict.fromkeys(p for path in paths for p in path):
            ways = set()
            for p, q in segments:
                if point == p or point == q:
                    other = q if point == p else p
                    ways.add((sign(other[0] - point[0]), sign(other[1] - point[1])))
                elif (p[0] == q[0] == point[0] and p[1] < point[1] < q[1]) or \
                        (p[1] == q[1] == point[1] and p[0] < point[0] < q[0]):
                    ways.update({(0, 1), (0, -1)} if p[0] == q[0] else {(1, 0), (-1, 0)})
            if len(ways) >= 3:
                dots.append((point, net))
    return dots


def sign(v):
    return (v > 0) - (v < 0)
