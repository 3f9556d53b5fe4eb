// The studio's automatic layout of blocks a model does not place: layered, along the wiring
// from left to right (a wire from a port on a block's right side to one on another's left
// side puts the second a layer further), parts hanging on a block's top or bottom ports (a
// spring-damper on a joint's support, a probe or a sensor on its axis) stacked above or below
// it, then cut into rows when it is much wider than the diagram (a long chain wraps, as text
// does), and the connected groups packed into rows of about the diagram's shape. All in
// diagram pixels; positions are given back in the file's layout units, on the snap grid.
import { blockGeometry } from "./geometry.js";
import { GRID, SCALE } from "./model.js";

const LAYER_GAP = 64; // px between layers (room for the wires between them)
const NODE_GAP = 52; // px between blocks of a layer (room for two wires between)
const SAT_GAP = 50; // px between a block and the parts stacked on it (room for a wire)
const ROW_GAP = 70; // px between the rows of a wrapped layout
const GROUP_GAP = 60; // px between connected groups
/** The diagram's shape (width over height) the layout aims at: the studio's canvas. */
export const ASPECT = 1.6;
/** How tall a layer may stand before it folds into columns, against the group's ideal height. */
const FOLDS = [0.5, 0.65, 0.8, 1.0, 1.3];

function ref(path) {
  const s = String(path);
  const i = s.indexOf(".");
  return i < 0 ? [s, ""] : [s.slice(0, i), s.slice(i + 1)];
}

/** A block's size and the side of each of its ports. */
function shapeOf(comp, body, ctx, typeInfo) {
  const info = typeInfo(comp.type, ctx);
  let ports = info ? info.ports : [];
  if (!info) {
    const names = new Set();
    for (const [a, b] of body.connections || []) {
      for (const p of [a, b]) {
        const [c, port] = ref(p);
        if (c === comp.name && port) names.add(port);
      }
    }
    ports = [...names].map((n) => ({ name: n, domain: "any" }));
  }
  const l = (body.layout || {})[comp.name] || {};
  const g = blockGeometry(ports, l.rotation || 0, !!l.flip);
  return { w: g.width, h: g.height, side: new Map(g.handles.map((h) => [h.port.name, h])) };
}

/**
 * Positions (layout units) for the components ``only`` of ``body`` (all without it),
 * placed below those the layout places.
 * @param {any} body a model or a definition
 * @param {string[] | null} only
 * @param {any} ctx what ``typeInfo`` needs to read the components' ports
 * @param {(type: string, ctx: any) => any} typeInfo
 */
export function layoutBlocks(body, only, ctx, typeInfo) {
  const comps = body.components || [];
  const want = new Set(only || comps.map((c) => c.name));
  const free = comps.filter((c) => want.has(c.name));
  if (!free.length) return {};
  const shape = new Map(free.map((c) => [c.name, shapeOf(c, body, ctx, typeInfo)]));
  const order = new Map(free.map((c, i) => [c.name, i]));
  // the wires among the blocks to place: [a, side of a's port, b, side of b's port]
  const links = [];
  for (const [pa, pb] of body.connections || []) {
    const [a, porta] = ref(pa);
    const [b, portb] = ref(pb);
    if (a === b || !shape.has(a) || !shape.has(b)) continue;
    const sa = shape.get(a).side.get(porta);
    const sb = shape.get(b).side.get(portb);
    links.push([a, sa ? sa.side : "right", b, sb ? sb.side : "left", pa, pb]);
  }
  const degree = new Map();
  for (const [a, , b] of links) for (const n of [a, b]) degree.set(n, (degree.get(n) || 0) + 1);

  // parts stacked on another: the lighter end of a wire to a top or bottom port (a block
  // with at most two wires) stands above or below the other end, by the side of its port
  const host = new Map(); // satellite -> [anchor, -1 above | +1 below]
  const hosts = new Set();
  for (const [a, sa, b, sb, pa, pb] of links) {
    if (![sa, sb].some((s) => s === "top" || s === "bottom")) continue;
    const [sat, anc, sanc] = degree.get(a) <= degree.get(b) ? [a, b, sb] : [b, a, sa];
    if (degree.get(sat) > 2 || host.has(sat) || host.has(anc) || hosts.has(sat)) continue;
    // a part on both the top and the bottom of one block (a spring-damper on a joint's support
    // and axis) stands above it, as in Modelica's diagrams
    const both = links.filter(([p, , q]) => (p === sat && q === anc) || (p === anc && q === sat)).length > 1;
    if (!both && sanc !== "top" && sanc !== "bottom") continue; // on a side port: next layer
    const where = both || sanc === "top" ? -1 : 1;
    const hook = shape.get(anc).side.get(ref(sat === a ? pb : pa)[1]);
    host.set(sat, [anc, where, hook ? hook.x : 0]);
    hosts.add(anc);
  }
  const top = (n) => (host.has(n) ? host.get(n)[0] : n);
  // units: a block with its satellites
  const units = new Map();
  for (const c of free) if (!host.has(c.name)) units.set(c.name, { id: c.name, above: [], below: [] });
  for (const [sat, [anc, where]] of host) units.get(top(anc))[where < 0 ? "above" : "below"].push(sat);
  for (const u of units.values()) {
    // above: stacked; below: side by side, each under the port it hangs on
    u.up = u.above.reduce((t, n) => t + shape.get(n).h + SAT_GAP, 0);
    u.below.sort((p, q) => host.get(p)[2] - host.get(q)[2]);
    u.dx = new Map();
    let right = -Infinity;
    for (const n of u.below) {
      const at = Math.max(right + NODE_GAP, host.get(n)[2] - shape.get(n).w / 2, 0);
      u.dx.set(n, at);
      right = at + shape.get(n).w;
    }
    u.w = Math.max(right, ...[u.id, ...u.above].map((m) => shape.get(m).w));
    const low = u.below.length ? SAT_GAP + Math.max(...u.below.map((n) => shape.get(n).h)) : 0;
    u.h = u.up + shape.get(u.id).h + low;
  }

  // the flow between units: right side to left side goes forward
  const out = new Map([...units.keys()].map((k) => [k, new Set()]));
  const undirected = new Map([...units.keys()].map((k) => [k, new Set()]));
  for (const [a, sa, b, sb] of links) {
    const ua = top(a);
    const ub = top(b);
    if (ua === ub) continue;
    undirected.get(ua).add(ub);
    undirected.get(ub).add(ua);
    if (sa === "left" && sb !== "left") out.get(ub).add(ua);
    else out.get(ua).add(ub);
  }
  const groups = [];
  const seen = new Set();
  for (const c of free) {
    const start = top(c.name);
    if (seen.has(start)) continue;
    const members = [];
    const todo = [start];
    seen.add(start);
    while (todo.length) {
      const n = todo.pop();
      members.push(n);
      for (const m of undirected.get(n)) if (!seen.has(m)) (seen.add(m), todo.push(m));
    }
    members.sort((p, q) => order.get(p) - order.get(q));
    groups.push(members);
  }

  // beside or below what the layout places already, whichever keeps the diagram's shape
  const given = comps.filter((c) => !want.has(c.name) && (body.layout || {})[c.name] && typeof body.layout[c.name].y === "number");
  const placed = given.map((c) => {
    const p = body.layout[c.name];
    const sh = shapeOf(c, body, ctx, typeInfo);
    return [p.x * SCALE, p.y * SCALE, p.x * SCALE + sh.w, p.y * SCALE + sh.h];
  });
  const fit = (w, h) => Math.max(w / ASPECT, h);
  // how tall a layer may stand before it folds: a few tried, the one that fits best kept
  let best = null;
  for (const fold of FOLDS) {
    const boxes = pack(groups.map((members) => layered(members, out, units, fold)));
    const fw = Math.max(0, ...[...boxes].map(([id, p]) => p.x + units.get(id).w));
    const fh = Math.max(0, ...[...boxes].map(([id, p]) => p.y + units.get(id).h));
    let choice = { boxes, x0: 0, y0: 0, score: fit(fw, fh) };
    if (placed.length) {
      const [gx0, gy0, gx1, gy1] = [0, 1, 2, 3].map((k) => (k < 2 ? Math.min : Math.max)(...placed.map((r) => r[k])));
      const below = fit(Math.max(gx1 - gx0, fw), gy1 - gy0 + GROUP_GAP + fh);
      const beside = fit(gx1 - gx0 + GROUP_GAP + fw, Math.max(gy1 - gy0, fh));
      choice = below <= beside ? { boxes, x0: gx0, y0: gy1 + GROUP_GAP, score: below } : { boxes, x0: gx1 + GROUP_GAP, y0: gy0, score: beside };
    }
    if (!best || choice.score < best.score - 1) best = choice;
  }
  const { boxes, x0, y0 } = best;
  // on the snap grid, rounded up down a stack so that no gap shrinks
  const snap = (v) => (Math.round(v / GRID) * GRID) / SCALE;
  const down = (v) => Math.ceil(v / GRID - 1e-9) * GRID;
  const pos = {};
  for (const [id, p] of boxes) {
    const u = units.get(id);
    const x = snap(x0 + p.x);
    let y = down(y0 + p.y);
    for (const n of [...u.above, id]) {
      pos[n] = { x, y: y / SCALE };
      y = down(y + shape.get(n).h + SAT_GAP);
    }
    for (const n of u.below) pos[n] = { x: snap(x0 + p.x + u.dx.get(n)), y: y / SCALE };
  }
  return pos;
}

/** One connected group laid out in layers (wrapped into rows when long): unit -> {x, y}. */
function layered(members, out, units, fold) {
  const inGroup = new Set(members);
  // break cycles where a depth-first walk from the sources closes them
  const state = new Map();
  const forward = new Map(members.map((m) => [m, []]));
  const incoming = new Map(members.map((m) => [m, 0]));
  for (const m of members) for (const n of out.get(m)) if (inGroup.has(n)) incoming.set(n, incoming.get(n) + 1);
  const starts = [...members.filter((m) => incoming.get(m) === 0), ...members];
  for (const s of starts) {
    if (state.has(s)) continue;
    const stack = [[s, [...out.get(s)].filter((n) => inGroup.has(n))]];
    state.set(s, 1);
    while (stack.length) {
      const [n, next] = stack[stack.length - 1];
      if (!next.length) {
        state.set(n, 2);
        stack.pop();
        continue;
      }
      const m = next.shift();
      if (state.get(m) === 1) continue; // a back edge: dropped
      forward.get(n).push(m);
      if (!state.has(m)) {
        state.set(m, 1);
        stack.push([m, [...out.get(m)].filter((k) => inGroup.has(k))]);
      }
    }
  }
  // layers by the longest path
  const layer = new Map(members.map((m) => [m, 0]));
  const topo = [];
  const indeg = new Map(members.map((m) => [m, 0]));
  for (const m of members) for (const n of forward.get(m)) indeg.set(n, indeg.get(n) + 1);
  const ready = members.filter((m) => indeg.get(m) === 0);
  while (ready.length) {
    const n = ready.shift();
    topo.push(n);
    for (const m of forward.get(n)) {
      layer.set(m, Math.max(layer.get(m), layer.get(n) + 1));
      indeg.set(m, indeg.get(m) - 1);
      if (indeg.get(m) === 0) ready.push(m);
    }
  }
  // a source feeding only a later layer moves up next to what it feeds (a signal source)
  for (const n of [...topo].reverse()) {
    const next = forward.get(n);
    if (next.length && ![...members].some((m) => forward.get(m).includes(n))) {
      layer.set(n, Math.min(...next.map((m) => layer.get(m))) - 1);
    }
  }
  const depth = Math.max(...members.map((m) => layer.get(m))) + 1;
  const layers = Array.from({ length: depth }, () => []);
  for (const m of topo) layers[layer.get(m)].push(m);
  // order within layers: barycentre sweeps, down and up
  const nbrs = new Map(members.map((m) => [m, []]));
  for (const m of members) {
    for (const n of forward.get(m)) {
      nbrs.get(m).push(n);
      nbrs.get(n).push(m);
    }
  }
  const rank = new Map();
  const renumber = () => layers.forEach((l) => l.forEach((m, i) => rank.set(m, i)));
  renumber();
  for (let sweep = 0; sweep < 6; sweep++) {
    const seq = sweep % 2 === 0 ? layers.slice(1) : layers.slice(0, -1).reverse();
    const side = sweep % 2 === 0 ? -1 : 1;
    for (const l of seq) {
      const bary = new Map();
      for (const m of l) {
        const near = nbrs.get(m).filter((n) => layer.get(n) === layer.get(m) + side);
        bary.set(m, near.length ? near.reduce((s, n) => s + rank.get(n), 0) / near.length : rank.get(m));
      }
      // on a tie, what leads on (a chain's next link) above a leaf (a body on a joint): the
      // chain then runs straight instead of down a staircase
      l.sort((p, q) => bary.get(p) - bary.get(q) || (forward.get(p).length ? 0 : 1) - (forward.get(q).length ? 0 : 1));
      l.forEach((m, i) => rank.set(m, i));
    }
  }
  // a layer much taller than the group is wide folds into columns side by side (twelve
  // signal sources feeding six drives stand in two columns, not one)
  const area = members.reduce((t, m) => t + (units.get(m).w + LAYER_GAP) * (units.get(m).h + NODE_GAP), 0);
  const tallest = Math.max(...members.map((m) => units.get(m).h));
  const reach = Math.max(tallest, Math.sqrt(area / ASPECT) * fold);
  const slots = []; // columns, in order: [layer, members]
  for (const [k, l] of layers.entries()) {
    let col = [];
    let h = 0;
    for (const m of l) {
      const dh = units.get(m).h + NODE_GAP;
      if (col.length && h + dh - NODE_GAP > reach) {
        slots.push([k, col]);
        col = [];
        h = 0;
      }
      col.push(m);
      h += dh;
    }
    if (col.length) slots.push([k, col]);
  }
  // heights: each block level with what feeds it, where there is room
  const y = new Map();
  const slotOf = new Map();
  slots.forEach(([, col], i) => col.forEach((m) => slotOf.set(m, i)));
  for (const [i, [, col]] of slots.entries()) {
    let floor = 0;
    for (const m of col) {
      const feeds = nbrs.get(m).filter((n) => y.has(n) && slotOf.get(n) < i);
      const want = feeds.length ? feeds.reduce((t, n) => t + y.get(n) + units.get(n).up, 0) / feeds.length - units.get(m).up : floor;
      const at = Math.max(floor, want);
      y.set(m, at);
      floor = at + units.get(m).h + NODE_GAP;
    }
  }
  const slotW = slots.map(([, col]) => Math.max(...col.map((m) => units.get(m).w)));
  const span = (k0, k1) => {
    let lo = Infinity;
    let hi = -Infinity;
    for (let k = k0; k < k1; k++) for (const m of slots[k][1]) (lo = Math.min(lo, y.get(m)), hi = Math.max(hi, y.get(m) + units.get(m).h));
    return [lo, hi];
  };
  const width = (k0, k1) => slotW.slice(k0, k1).reduce((t, w) => t + w + LAYER_GAP, 0) - LAYER_GAP;
  // cut into rows where that brings the group nearer the diagram's shape
  const n = slots.length;
  let best = null;
  for (let rows = 1; rows <= n; rows++) {
    const per = Math.ceil(n / rows);
    let h = 0;
    let w = 0;
    const cuts = [];
    for (let k = 0; k < n; k += per) {
      const [lo, hi] = span(k, Math.min(n, k + per));
      cuts.push([k, lo, h]);
      h += hi - lo + ROW_GAP;
      w = Math.max(w, width(k, Math.min(n, k + per)));
    }
    const score = Math.max(w / ASPECT, h - ROW_GAP);
    if (!best || score < best.score - 1) best = { score, per, cuts, w, h: h - ROW_GAP };
  }
  const at = new Map();
  for (const [k0, lo, top] of best.cuts) {
    let x = 0;
    for (let k = k0; k < Math.min(n, k0 + best.per); k++) {
      for (const m of slots[k][1]) at.set(m, { x, y: top + y.get(m) - lo });
      x += slotW[k] + LAYER_GAP;
    }
  }
  return { at, w: best.w, h: best.h };
}

/** Groups packed in rows, the widest first, to about the diagram's shape: unit -> {x, y}. */
function pack(groups) {
  const area = groups.reduce((s, g) => s + (g.w + GROUP_GAP) * (g.h + GROUP_GAP), 0);
  const widest = Math.max(...groups.map((g) => g.w));
  const limit = Math.max(widest, Math.sqrt(area * ASPECT));
  const sorted = [...groups].sort((a, b) => b.h - a.h);
  const out = new Map();
  let x = 0;
  let y = 0;
  let rowH = 0;
  for (const g of sorted) {
    if (x > 0 && x + g.w > limit) {
      x = 0;
      y += rowH + GROUP_GAP;
      rowH = 0;
    }
    for (const [m, p] of g.at) out.set(m, { x: x + p.x, y: y + p.y });
    x += g.w + GROUP_GAP;
    rowH = Math.max(rowH, g.h);
  }
  return out;
}
