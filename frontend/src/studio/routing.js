// Orthogonal wires around the blocks of a diagram. Each wire is a cheapest path on a grid of
// tracks (lines beside every block, through every port, and spread across the gaps between),
// priced by length, bends and crossings. A wire may run along a wire of its own net (they
// merge, as one node of the circuit), never along another net's, never through a block or the
// margin around it, and never bends or ends on another net's wire (that would read as a
// junction). When blocks move, only the wires that must change are routed again: those of the
// moved blocks and those the moved blocks now cover; the others stay where the user saw them.

/** Pixels a track keeps from a block (a wire leaves its port straight through this margin). */
export const CLEAR = 16;
/** Pixels between neighbouring parallel tracks. */
export const TRACK = 8;
/** Pixels from a port's handle kept for its own net: past the first track beside its block. */
const STUB = CLEAR + 4;
const BEND = 30;
const CROSS = 14;
const MERGE = 0.35; // the price of a pixel along a wire of the same net, against 1 elsewhere
const CLASH = 4000; // a pixel along another net's wire, when there is no other way
const MAX_FILL = 6; // extra tracks across one gap
const NEAR = 3; // tracks closer than this are one track
const RETRIES = 3; // rounds of routing a crowded diagram again, the wires that failed first

const DIRS = [[1, 0], [-1, 0], [0, 1], [0, -1]];

function lowerBound(list, v) {
  let lo = 0;
  let hi = list.length;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (list[mid] < v) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/** Sorted track positions: ``exact`` ones as given, the others where no track is near. */
function tracks(exact, wanted, dense = 1) {
  const lines = [...new Set(exact)].sort((a, b) => a - b);
  for (const v of [...new Set(wanted)].sort((a, b) => a - b)) {
    const i = lowerBound(lines, v);
    if ((i >= lines.length || lines[i] - v >= NEAR) && (i === 0 || v - lines[i - 1] >= NEAR)) lines.splice(i, 0, v);
  }
  const fill = [];
  for (let i = 0; i + 1 < lines.length; i++) {
    const gap = lines[i + 1] - lines[i];
    const n = Math.min(MAX_FILL * dense, Math.floor((gap * dense) / TRACK) - 1);
    for (let k = 1; k <= n; k++) fill.push(Math.round(lines[i] + (gap * k) / (n + 1)));
  }
  return [...new Set([...lines, ...fill])].sort((a, b) => a - b);
}

/** A binary heap of (priority, state) pairs. */
class Heap {
  constructor() {
    this.keys = [];
    this.vals = [];
    this.key = 0; // the priority of the last state popped
  }

  push(k, v) {
    const { keys, vals } = this;
    let i = keys.length;
    keys.push(k);
    vals.push(v);
    while (i > 0) {
      const up = (i - 1) >> 1;
      if (keys[up] <= k) break;
      keys[i] = keys[up];
      vals[i] = vals[up];
      i = up;
    }
    keys[i] = k;
    vals[i] = v;
  }

  pop() {
    const { keys, vals } = this;
    const top = vals[0];
    this.key = keys[0];
    const k = keys.pop();
    const v = vals.pop();
    const n = keys.length;
    if (n) {
      let i = 0;
      for (;;) {
        let c = 2 * i + 1;
        if (c >= n) break;
        if (c + 1 < n && keys[c + 1] < keys[c]) c++;
        if (keys[c] >= k) break;
        keys[i] = keys[c];
        vals[i] = vals[c];
        i = c;
      }
      keys[i] = k;
      vals[i] = v;
    }
    return top;
  }

  get size() {
    return this.keys.length;
  }
}

/** Points without repeats and without corners that do not turn. */
export function simplify(points) {
  const out = [];
  for (const p of points) {
    const last = out[out.length - 1];
    if (last && last.x === p.x && last.y === p.y) continue;
    if (out.length >= 2) {
      const a = out[out.length - 2];
      if ((a.x === last.x && last.x === p.x) || (a.y === last.y && last.y === p.y)) out.pop();
    }
    out.push(p);
  }
  return out;
}

/**
 * The grid of tracks for ``rects`` and the wires' ends, with what blocks it and what the
 * wires already drawn occupy.
 */
class Grid {
  constructor(rects, ends, kept, dense = 1) {
    const ex = [];
    const ey = [];
    const wx = [];
    const wy = [];
    for (const r of rects) {
      wx.push(r.x0 - CLEAR, r.x1 + CLEAR);
      wy.push(r.y0 - CLEAR, r.y1 + CLEAR);
    }
    for (const p of ends) {
      ex.push(p.x);
      ey.push(p.y);
    }
    for (const points of kept) {
      for (const p of points) {
        ex.push(p.x);
        ey.push(p.y);
      }
    }
    // and a few tracks around everything, for the wires that go round the outside
    for (const [exact, wanted] of [[ex, wx], [ey, wy]]) {
      const lo = Math.min(...exact, ...wanted);
      const hi = Math.max(...exact, ...wanted);
      for (let k = 1; k <= 4; k++) wanted.push(lo - k * TRACK, hi + k * TRACK);
    }
    this.xs = tracks(ex, wx, dense);
    this.ys = tracks(ey, wy, dense);
    this.nx = this.xs.length;
    this.ny = this.ys.length;
    const n = this.nx * this.ny;
    this.blockedH = new Uint8Array(n); // the edge from node i to its right neighbour
    this.blockedV = new Uint8Array(n); // the edge from node i to the one below
    this.edgeH = new Int32Array(n); // net + 1 of a wire along that edge, -1 for several
    this.edgeV = new Int32Array(n);
    this.passH = new Int32Array(n); // net + 1 of a wire through the node, left to right
    this.passV = new Int32Array(n);
    this.stop = new Int32Array(n); // net + 1 of a wire that bends or ends at the node
    for (const r of rects) this.block(r, ends);
  }

  index(x, y) {
    const ix = lowerBound(this.xs, x - 0.01);
    const iy = lowerBound(this.ys, y - 0.01);
    if (ix >= this.nx || iy >= this.ny || Math.abs(this.xs[ix] - x) > 0.01 || Math.abs(this.ys[iy] - y) > 0.01) return -1;
    return iy * this.nx + ix;
  }

  /** Close the edges in a block and its margin, but the straight ways out of its ports. */
  block(r, ends) {
    const { xs, ys, nx } = this;
    const m = CLEAR - 2;
    const ox = new Set();
    const oy = new Set();
    for (const p of ends) {
      // a port of this block: its stub is the way out
      const onX = p.x >= r.x0 - m && p.x <= r.x1 + m;
      const onY = p.y >= r.y0 - m && p.y <= r.y1 + m;
      if (onX && onY) {
        if (p.dir[0] !== 0) oy.add(p.y);
        else ox.add(p.x);
      }
    }
    const iy0 = lowerBound(ys, r.y0 - m);
    const iy1 = lowerBound(ys, r.y1 + m + 0.01);
    const ix0 = lowerBound(xs, r.x0 - m);
    const ix1 = lowerBound(xs, r.x1 + m + 0.01);
    // horizontal edges (ix -> ix+1) on rows inside the margin that overlap the box
    for (let iy = iy0; iy < iy1; iy++) {
      const inside = ys[iy] > r.y0 - 0.5 && ys[iy] < r.y1 + 0.5;
      if (!inside && oy.has(ys[iy])) continue;
      for (let ix = Math.max(0, ix0 - 1); ix < Math.min(nx - 1, ix1); ix++) {
        const a = xs[ix];
        const b = xs[ix + 1];
        if (b <= r.x0 - m || a >= r.x1 + m) continue;
        if (oy.has(ys[iy]) && (b <= r.x0 + 0.5 || a >= r.x1 - 0.5)) continue;
        this.blockedH[iy * nx + ix] = 1;
      }
    }
    for (let ix = ix0; ix < ix1; ix++) {
      const inside = xs[ix] > r.x0 - 0.5 && xs[ix] < r.x1 + 0.5;
      if (!inside && ox.has(xs[ix])) continue;
      for (let iy = Math.max(0, iy0 - 1); iy < Math.min(this.ny - 1, iy1); iy++) {
        const a = ys[iy];
        const b = ys[iy + 1];
        if (b <= r.y0 - m || a >= r.y1 + m) continue;
        if (ox.has(xs[ix]) && (b <= r.y0 + 0.5 || a >= r.y1 - 0.5)) continue;
        this.blockedV[iy * nx + ix] = 1;
      }
    }
  }

  /** Mark the wire ``points`` of net ``net`` as drawn. */
  occupy(points, net) {
    const { xs, ys, nx } = this;
    const tag = net + 1;
    const put = (arr, i) => {
      arr[i] = arr[i] === 0 || arr[i] === tag ? tag : -1;
    };
    for (let k = 0; k + 1 < points.length; k++) {
      const p = points[k];
      const q = points[k + 1];
      if (p.y === q.y) {
        const lo = Math.min(p.x, q.x);
        const hi = Math.max(p.x, q.x);
        // every track within a pixel of the segment counts as taken
        for (let iy = lowerBound(ys, p.y - 1.5); iy < this.ny && ys[iy] <= p.y + 1.5; iy++) {
          for (let ix = lowerBound(xs, lo); ix < nx && xs[ix] <= hi; ix++) {
            if (xs[ix] < hi && ix + 1 < nx) put(this.edgeH, iy * nx + ix);
            if (xs[ix] > lo && xs[ix] < hi) put(this.passH, iy * nx + ix);
          }
        }
      } else {
        const lo = Math.min(p.y, q.y);
        const hi = Math.max(p.y, q.y);
        for (let ix = lowerBound(xs, p.x - 1.5); ix < nx && xs[ix] <= p.x + 1.5; ix++) {
          for (let iy = lowerBound(ys, lo); iy < this.ny && ys[iy] <= hi; iy++) {
            if (ys[iy] < hi && iy + 1 < this.ny) put(this.edgeV, iy * nx + ix);
            if (ys[iy] > lo && ys[iy] < hi) put(this.passV, iy * nx + ix);
          }
        }
      }
    }
    for (const p of points) {
      const i = this.index(p.x, p.y);
      if (i >= 0) put(this.stop, i);
    }
  }

  /**
   * The cheapest wire from ``a`` to ``b`` (ends with their outward directions) for net
   * ``net``, or null; ``strict``: never along another net's wire.
   */
  search(a, b, net, strict) {
    const { xs, ys, nx, ny } = this;
    const start = this.index(a.x, a.y);
    const goal = this.index(b.x, b.y);
    if (start < 0 || goal < 0) return null;
    const tag = net + 1;
    const other = (v) => v !== 0 && v !== tag;
    const d0 = DIRS.findIndex(([dx, dy]) => dx === a.dir[0] && dy === a.dir[1]);
    const dGoal = DIRS.findIndex(([dx, dy]) => dx === -b.dir[0] && dy === -b.dir[1]);
    const gx = b.x;
    const gy = b.y;
    // the searches of one grid share their tables: a state's entries count only when stamped
    // with this search's number
    if (!this.best) {
      this.best = new Float64Array(nx * ny * 4);
      this.back = new Int32Array(nx * ny * 4);
      this.seen = new Int32Array(nx * ny * 4);
      this.round = 0;
    }
    const { best, back, seen } = this;
    const round = ++this.round;
    const heap = new Heap();
    const s0 = start * 4 + d0;
    best[s0] = 0;
    back[s0] = -1;
    seen[s0] = round;
    heap.push(0, s0);
    let found = -1;
    while (heap.size) {
      const s = heap.pop();
      const key = heap.key;
      const node = s >> 2;
      const d = s & 3;
      const cost = best[s];
      if (key > cost + Math.abs(xs[node % nx] - gx) + Math.abs(ys[Math.floor(node / nx)] - gy) + 1e-9) continue;
      if (node === goal && d === dGoal) {
        found = s;
        break;
      }
      const ix = node % nx;
      const iy = (node - ix) / nx;
      for (let d2 = 0; d2 < 4; d2++) {
        if ((d2 ^ 1) === d && d2 !== d) continue; // no turning back
        if (node === start && d2 !== d0) continue; // out of a port straight
        let extra = 0;
        if (d2 !== d) {
          // a bend on another net's wire reads as a junction
          if (other(this.stop[node]) || other(this.passH[node]) || other(this.passV[node])) {
            if (strict) continue;
            extra += CLASH;
          }
          extra += BEND;
        }
        const [dx, dy] = DIRS[d2];
        const jx = ix + dx;
        const jy = iy + dy;
        if (jx < 0 || jy < 0 || jx >= nx || jy >= ny) continue;
        const next = jy * nx + jx;
        const e = dx !== 0 ? iy * nx + Math.min(ix, jx) : Math.min(iy, jy) * nx + ix;
        if (dx !== 0 ? this.blockedH[e] : this.blockedV[e]) continue;
        const length = dx !== 0 ? Math.abs(xs[jx] - xs[ix]) : Math.abs(ys[jy] - ys[iy]);
        const along = dx !== 0 ? this.edgeH[e] : this.edgeV[e];
        let price = length;
        if (along === tag) price = length * MERGE;
        else if (along !== 0) {
          if (strict) continue;
          price = length * CLASH;
        }
        // through another net's bend or end: it would look joined
        if (next !== goal && other(this.stop[next])) {
          if (strict) continue;
          price += CLASH;
        }
        const across = dx !== 0 ? this.passV[next] : this.passH[next];
        if (other(across)) extra += CROSS;
        const ns = next * 4 + d2;
        const nc = cost + price + extra;
        if (seen[ns] !== round || nc < best[ns]) {
          seen[ns] = round;
          best[ns] = nc;
          back[ns] = s;
          // a distance at full price: far quicker than an admissible guess, and the wires
          // it finds differ little (merging with one's own net is the only cheaper way)
          const h = Math.abs(xs[jx] - gx) + Math.abs(ys[jy] - gy);
          heap.push(nc + h, ns);
        }
      }
    }
    if (found < 0) return null;
    const points = [];
    for (let s = found; s >= 0; s = back[s]) {
      const node = s >> 2;
      points.push({ x: xs[node % nx], y: ys[Math.floor(node / nx)] });
    }
    return simplify(points.reverse());
  }
}

/** A wire's identity for re-use: where it starts and ends, and its net. */
function wireKey(w) {
  return `${w.net}|${w.a.x},${w.a.y},${w.a.dir}|${w.b.x},${w.b.y},${w.b.dir}`;
}

function rectKey(r) {
  return `${r.x0},${r.y0},${r.x1},${r.y1}`;
}

/** Whether the segment p-q passes through the inside of rectangle ``r`` grown by ``m``. */
export function segmentHits(p, q, r, m = 0) {
  const x0 = Math.min(p.x, q.x);
  const x1 = Math.max(p.x, q.x);
  const y0 = Math.min(p.y, q.y);
  const y1 = Math.max(p.y, q.y);
  return x1 > r.x0 - m && x0 < r.x1 + m && y1 > r.y0 - m && y0 < r.y1 + m;
}

/**
 * Wires routed around blocks.
 *
 * @param {{id: string, x0: number, y0: number, x1: number, y1: number}[]} rects the blocks
 * @param {{id: string, net: number, a: {x: number, y: number, dir: number[]},
 *   b: {x: number, y: number, dir: number[]}}[]} wires each wire's ends (on the outer edge of
 *   its ports' handles, with the direction a wire leaves them) and its net: wires of one net
 *   may share a track
 * @param {{rects: Map<string, string>, wires: Map<string, {key: string, points: any[]}>} | null}
 *   before the answer for the diagram as it was: wires that need not change are kept
 * @returns {{rects: Map<string, string>, wires: Map<string, {key: string, points: any[]}>,
 *   routed: number, clashes: string[]}} each wire's points; ``routed``: how many were routed
 *   this time; ``clashes``: the wires that found no way but along another net's wire
 */
export function routeWires(rects, wires, before = null) {
  const rectKeys = new Map(rects.map((r) => [r.id, rectKey(r)]));
  const moved = before ? rects.filter((r) => before.rects.get(r.id) !== rectKeys.get(r.id)) : rects;
  const keep = new Map();
  if (before) {
    for (const w of wires) {
      const old = before.wires.get(w.id);
      if (!old || old.key !== wireKey(w)) continue;
      let hit = false;
      for (let k = 0; k + 1 < old.points.length && !hit; k++) {
        hit = moved.some((r) => segmentHits(old.points[k], old.points[k + 1], r, CLEAR - 4));
      }
      if (!hit) keep.set(w.id, old);
    }
  }
  const todo = wires.filter((w) => !keep.has(w.id));
  if (before && !todo.length) return { rects: rectKeys, wires: keep, routed: 0, clashes: [] };
  let out = route(rects, wires, keep, todo);
  // a wire that found no way of its own goes first next time (a crowded diagram): a few rounds
  for (let round = 0; round < RETRIES && out.clashes.length && !keep.size; round++) {
    const first = new Set(out.clashes);
    const again = route(rects, wires, keep, todo, first);
    if (again.clashes.length < out.clashes.length) out = again;
    else break;
  }
  // still crowded: tracks twice as close together
  if (out.clashes.length && !keep.size) {
    const dense = route(rects, wires, keep, todo, new Set(out.clashes), 2);
    if (dense.clashes.length < out.clashes.length) out = dense;
  }
  // a wire that found no way but along another net's: all of them again, from scratch
  if (before && out.clashes.length) return routeWires(rects, wires, null);
  return { rects: rectKeys, wires: out.wires, routed: todo.length, clashes: out.clashes };
}

/**
 * A router with a memory: each call routes again only the wires that its diagram's changes
 * concern (see ``routeWires``).
 */
export class WireRouter {
  constructor() {
    this.last = null;
  }

  /** Each wire's points (a Map from wire id), for the diagram as it is now. */
  route(rects, wires) {
    this.last = routeWires(rects, wires, this.last);
    return this.last;
  }
}

function route(rects, wires, keep, todo, first = new Set(), dense = 1) {
  const ends = wires.flatMap((w) => [w.a, w.b]);
  const grid = new Grid(rects, ends, [...keep.values()].map((k) => k.points), dense);
  const byId = new Map(wires.map((w) => [w.id, w]));
  // each port's way out is its net's: another net running along it would leave the port
  // no way to go
  for (const w of wires) {
    for (const e of [w.a, w.b]) grid.occupy([e, { x: e.x + e.dir[0] * STUB, y: e.y + e.dir[1] * STUB }], w.net);
  }
  for (const [id, k] of keep) grid.occupy(k.points, byId.get(id).net);
  // the nets with the shortest reach first (they have the fewest ways), a net's wires together
  const reach = new Map();
  for (const w of todo) {
    const d = Math.abs(w.a.x - w.b.x) + Math.abs(w.a.y - w.b.y);
    reach.set(w.net, Math.max(reach.get(w.net) || 0, d));
  }
  const ahead = new Set([...todo].filter((w) => first.has(w.id)).map((w) => w.net));
  const rank = (w) => (ahead.has(w.net) ? 0 : 1);
  const order = [...todo].sort((p, q) => rank(p) - rank(q) || reach.get(p.net) - reach.get(q.net) || p.net - q.net || String(p.id).localeCompare(String(q.id)));
  const result = new Map(keep);
  const clashes = [];
  for (const w of order) {
    let points = grid.search(w.a, w.b, w.net, true);
    if (!points) {
      clashes.push(w.id);
      points = grid.search(w.a, w.b, w.net, false);
    }
    if (!points) {
      // no way around at all (blocks on top of each other): a plain elbow
      points = simplify([w.a, { x: w.b.x, y: w.a.y }, w.b]);
    }
    grid.occupy(points, w.net);
    result.set(w.id, { key: wireKey(w), points });
  }
  return { wires: result, clashes };
}

/**
 * What is wrong with routed wires, as a reader of the diagram sees it: pairs of segments of
 * different nets on one track (collinear within ``tol`` pixels, overlapping by more than
 * ``tol``), and segments through a block.
 *
 * @param {{net: number, points: {x: number, y: number}[]}[]} drawn
 * @param {{x0: number, y0: number, x1: number, y1: number}[]} rects
 */
export function routingFaults(drawn, rects, tol = 1) {
  const segs = [];
  for (const w of drawn) {
    for (let k = 0; k + 1 < w.points.length; k++) segs.push({ p: w.points[k], q: w.points[k + 1], net: w.net });
  }
  let shared = 0;
  for (let i = 0; i < segs.length; i++) {
    for (let j = i + 1; j < segs.length; j++) {
      const s = segs[i];
      const t = segs[j];
      if (s.net === t.net) continue;
      for (const [u, v] of [["x", "y"], ["y", "x"]]) {
        // both along v, at the same u
        if (Math.abs(s.p[u] - s.q[u]) > tol || Math.abs(t.p[u] - t.q[u]) > tol || Math.abs(s.p[u] - t.p[u]) > tol) continue;
        const lo = Math.max(Math.min(s.p[v], s.q[v]), Math.min(t.p[v], t.q[v]));
        const hi = Math.min(Math.max(s.p[v], s.q[v]), Math.max(t.p[v], t.q[v]));
        if (hi - lo > tol) {
          shared += 1;
          break;
        }
      }
    }
  }
  let through = 0;
  for (const s of segs) if (rects.some((r) => segmentHits(s.p, s.q, r, -tol))) through += 1;
  return { shared, through };
}
