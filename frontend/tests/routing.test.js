// The wire router and the layout, checked by geometry written here (not by the router's own
// fault count): every segment horizontal or vertical, wires ending on their ports and leaving
// them straight, never two nets on one track, never a segment through a block; a moved block
// re-routes only the wires it concerns; a long chain wraps into rows.
import { describe, expect, it } from "vitest";
import { CLEAR, WireRouter, routeWires } from "../src/studio/routing.js";
import { ASPECT, layoutBlocks } from "../src/studio/layout.js";

const TOL = 1;

/** Blocks in a grid, each with ``ports`` ports on its left and on its right. */
function grid(cols, rows, dx = 190, dy = 130) {
  const rects = [];
  for (let r = 0; r < rows; r++) for (let c = 0; c < cols; c++) rects.push({ id: `b${r}_${c}`, x0: c * dx, y0: r * dy, x1: c * dx + 116, y1: r * dy + 70 });
  return rects;
}

function port(rect, side, k) {
  const y = rect.y0 + 15 + k * 20;
  return side === "right" ? { x: rect.x1 + 7, y, dir: [1, 0] } : { x: rect.x0 - 7, y, dir: [-1, 0] };
}

/** Many wires between pseudo-random blocks, each port used once: one net per wire. */
function tangle(rects, count, seed = 7) {
  let s = seed;
  const rand = () => ((s = (s * 1103515245 + 12345) % 2147483648) / 2147483648);
  const used = new Map();
  const wires = [];
  for (let i = 0; wires.length < count && i < count * 20; i++) {
    const a = rects[Math.floor(rand() * rects.length)];
    const b = rects[Math.floor(rand() * rects.length)];
    const ka = used.get(`${a.id}r`) || 0;
    const kb = used.get(`${b.id}l`) || 0;
    if (a === b || ka > 2 || kb > 2) continue;
    used.set(`${a.id}r`, ka + 1);
    used.set(`${b.id}l`, kb + 1);
    wires.push({ id: `w${wires.length}`, net: wires.length, a: port(a, "right", ka), b: port(b, "left", kb) });
  }
  return wires;
}

function segments(routes, wires) {
  const out = [];
  for (const w of wires) {
    const pts = routes.get(w.id).points;
    for (let k = 0; k + 1 < pts.length; k++) out.push({ p: pts[k], q: pts[k + 1], net: w.net, id: w.id });
  }
  return out;
}

function problems(routes, wires, rects) {
  const segs = segments(routes, wires);
  const bad = [];
  for (const { p, q, id } of segs) {
    if (Math.abs(p.x - q.x) > TOL && Math.abs(p.y - q.y) > TOL) bad.push(`${id} slanted`);
    for (const r of rects) {
      if (Math.max(p.x, q.x) > r.x0 + TOL && Math.min(p.x, q.x) < r.x1 - TOL && Math.max(p.y, q.y) > r.y0 + TOL && Math.min(p.y, q.y) < r.y1 - TOL) bad.push(`${id} through ${r.id}`);
    }
  }
  for (let i = 0; i < segs.length; i++) {
    for (let j = i + 1; j < segs.length; j++) {
      const s = segs[i];
      const t = segs[j];
      if (s.net === t.net) continue;
      const vertical = Math.abs(s.p.x - s.q.x) <= TOL && Math.abs(t.p.x - t.q.x) <= TOL && Math.abs(s.p.x - t.p.x) <= TOL;
      const horizontal = Math.abs(s.p.y - s.q.y) <= TOL && Math.abs(t.p.y - t.q.y) <= TOL && Math.abs(s.p.y - t.p.y) <= TOL;
      const [u, v] = vertical ? ["y", "y"] : ["x", "x"];
      if (!vertical && !horizontal) continue;
      const lo = Math.max(Math.min(s.p[u], s.q[u]), Math.min(t.p[v], t.q[v]));
      const hi = Math.min(Math.max(s.p[u], s.q[u]), Math.max(t.p[v], t.q[v]));
      if (hi - lo > TOL) bad.push(`${s.id} / ${t.id} on one track`);
    }
  }
  for (const w of wires) {
    const pts = routes.get(w.id).points;
    const [first, second] = pts;
    const [last, before] = [pts[pts.length - 1], pts[pts.length - 2]];
    if (first.x !== w.a.x || first.y !== w.a.y || last.x !== w.b.x || last.y !== w.b.y) bad.push(`${w.id} off its ports`);
    // out of each port straight, away from its block
    if (Math.sign(second.x - first.x) !== w.a.dir[0] || Math.sign(second.y - first.y) !== w.a.dir[1]) bad.push(`${w.id} leaves a crooked`);
    if (Math.sign(before.x - last.x) !== w.b.dir[0] || Math.sign(before.y - last.y) !== w.b.dir[1]) bad.push(`${w.id} enters b crooked`);
  }
  return bad;
}

describe("routing", () => {
  it("goes round a block in the way", () => {
    const rects = [
      { id: "a", x0: 0, y0: 0, x1: 116, y1: 64 },
      { id: "m", x0: 200, y0: 0, x1: 316, y1: 64 },
      { id: "b", x0: 400, y0: 0, x1: 516, y1: 64 },
    ];
    const wires = [{ id: "w", net: 0, a: { x: 123, y: 32, dir: [1, 0] }, b: { x: 393, y: 32, dir: [-1, 0] } }];
    const { wires: routes } = routeWires(rects, wires);
    expect(problems(routes, wires, rects)).toEqual([]);
    // and keeps its distance from the block it passes
    const ys = routes.get("w").points.map((p) => p.y);
    expect(Math.min(...ys) <= -CLEAR || Math.max(...ys) >= 64 + CLEAR).toBe(true);
  });

  it("keeps 45 wires of different nets on tracks of their own, among 42 blocks", () => {
    const rects = grid(7, 6);
    // as many wires as blocks, as in arm_computed_torque (41 wires, 35 blocks), each net
    // between two random blocks of the grid: most cross the diagram
    const wires = tangle(rects, 45);
    expect(wires.length).toBe(45);
    const out = routeWires(rects, wires);
    expect(out.clashes).toEqual([]);
    expect(problems(out.wires, wires, rects)).toEqual([]);
  });

  it("lets the wires of one net share a track", () => {
    const rects = [
      { id: "s", x0: 0, y0: 100, x1: 116, y1: 164 },
      { id: "t1", x0: 300, y0: 0, x1: 416, y1: 64 },
      { id: "t2", x0: 300, y0: 200, x1: 416, y1: 264 },
    ];
    const from = { x: 123, y: 132, dir: [1, 0] };
    const wires = [
      { id: "w1", net: 3, a: from, b: { x: 293, y: 32, dir: [-1, 0] } },
      { id: "w2", net: 3, a: from, b: { x: 293, y: 232, dir: [-1, 0] } },
    ];
    const { wires: routes } = routeWires(rects, wires);
    expect(problems(routes, wires, rects)).toEqual([]);
    const [p, q] = [routes.get("w1").points, routes.get("w2").points];
    // they leave the port together: the first bend is one point of both
    expect(p[1]).toEqual(q[1]);
  });

  it("routes again only the wires of a moved block and those it now covers", () => {
    const rects = grid(5, 4);
    const wires = tangle(rects, 24, 3);
    const router = new WireRouter();
    const first = router.route(rects, wires);
    expect(first.routed).toBe(wires.length);
    const before = new Map([...first.wires].map(([id, r]) => [id, JSON.stringify(r.points)]));
    // b1_2 moves down by 40 px: its ports with it
    const moved = rects.map((r) => (r.id === "b1_2" ? { ...r, y0: r.y0 + 40, y1: r.y1 + 40 } : r));
    const mr = moved.find((r) => r.id === "b1_2");
    const shift = (e, r) => (Math.abs(e.x - (r.x1 + 7)) < 1 || Math.abs(e.x - (r.x0 - 7)) < 1) && e.y > r.y0 && e.y < r.y1 ? { ...e, y: e.y + 40 } : e;
    const old = rects.find((r) => r.id === "b1_2");
    const wires2 = wires.map((w) => ({ ...w, a: shift(w.a, old), b: shift(w.b, old) }));
    const second = router.route(moved, wires2);
    expect(problems(second.wires, wires2, moved)).toEqual([]);
    const own = wires2.filter((w, i) => w.a !== wires[i].a || w.b !== wires[i].b).map((w) => w.id);
    expect(own.length).toBeGreaterThan(0);
    const covered = wires.filter((w) => {
      const pts = first.wires.get(w.id).points;
      return pts.some((p, k) => k + 1 < pts.length && Math.max(p.x, pts[k + 1].x) > mr.x0 - CLEAR && Math.min(p.x, pts[k + 1].x) < mr.x1 + CLEAR && Math.max(p.y, pts[k + 1].y) > mr.y0 - CLEAR && Math.min(p.y, pts[k + 1].y) < mr.y1 + CLEAR);
    });
    const allowed = new Set([...own, ...covered.map((w) => w.id)]);
    expect(second.routed).toBeLessThan(wires.length);
    for (const w of wires2) {
      if (!allowed.has(w.id)) expect(JSON.stringify(second.wires.get(w.id).points)).toBe(before.get(w.id));
    }
  });

  it("still draws a wire between blocks piled on each other", () => {
    const rects = [
      { id: "a", x0: 0, y0: 0, x1: 116, y1: 64 },
      { id: "b", x0: 10, y0: 10, x1: 126, y1: 74 },
    ];
    const wires = [{ id: "w", net: 0, a: { x: 123, y: 32, dir: [1, 0] }, b: { x: 3, y: 42, dir: [-1, 0] } }];
    const pts = routeWires(rects, wires).wires.get("w").points;
    expect(pts[0]).toMatchObject({ x: 123, y: 32 });
    expect(pts[pts.length - 1]).toMatchObject({ x: 3, y: 42 });
  });
});

/** Ports of the test's types: a joint (frames left and right, flanges top and bottom), a body. */
const TYPES = {
  J: { ports: [{ name: "frame_a", domain: "frame" }, { name: "frame_b", domain: "frame" }, { name: "support", domain: "rotational" }, { name: "axis", domain: "rotational" }] },
  B: { ports: [{ name: "frame_a", domain: "frame" }] },
  L: { ports: [{ name: "frame_a", domain: "frame" }, { name: "frame_b", domain: "frame" }] },
  S: { ports: [{ name: "flange_a", domain: "rotational" }, { name: "flange_b", domain: "rotational" }] },
};
const info = (type) => TYPES[type] || null;

function chainModel(n) {
  const components = [{ name: "g", type: "L" }];
  const connections = [];
  let prev = "g.frame_b";
  for (let i = 0; i < n; i++) {
    components.push({ name: `j${i}`, type: "J" }, { name: `b${i}`, type: "B" }, { name: `l${i}`, type: "L" });
    connections.push([prev, `j${i}.frame_a`], [`j${i}.frame_b`, `b${i}.frame_a`], [`j${i}.frame_b`, `l${i}.frame_a`]);
    prev = `l${i}.frame_b`;
  }
  return { components, connections, layout: {} };
}

function boxes(body, pos) {
  return body.components.map((c) => {
    const ports = TYPES[c.type].ports.length;
    return { id: c.name, x0: pos[c.name].x * 1.5, y0: pos[c.name].y * 1.5, x1: pos[c.name].x * 1.5 + 116, y1: pos[c.name].y * 1.5 + (ports > 2 ? 64 : 64) };
  });
}

describe("layout", () => {
  it("wraps a 32-link chain into rows near the diagram's shape, no block on another", () => {
    const body = chainModel(32);
    const pos = layoutBlocks(body, null, {}, info);
    const rects = boxes(body, pos);
    for (let i = 0; i < rects.length; i++) {
      for (let j = i + 1; j < rects.length; j++) {
        const [a, b] = [rects[i], rects[j]];
        expect(a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1, `${a.id} on ${b.id}`).toBe(false);
      }
    }
    const w = Math.max(...rects.map((r) => r.x1)) - Math.min(...rects.map((r) => r.x0));
    const h = Math.max(...rects.map((r) => r.y1)) - Math.min(...rects.map((r) => r.y0));
    expect(w / h).toBeGreaterThan(ASPECT / 2);
    expect(w / h).toBeLessThan(ASPECT * 2);
    // each joint level with the link before it: the chain runs straight along its rows
    const level = body.components.filter((c) => c.type === "J" && c.name !== "j0").filter((c) => pos[c.name].y === pos[`l${Number(c.name.slice(1)) - 1}`].y);
    expect(level.length).toBeGreaterThan(24);
  });

  it("stands a spring-damper on a joint's support and axis above the joint", () => {
    const body = {
      components: [{ name: "j", type: "J" }, { name: "s", type: "S" }],
      connections: [["s.flange_a", "j.support"], ["s.flange_b", "j.axis"]],
      layout: {},
    };
    const pos = layoutBlocks(body, null, {}, info);
    expect(pos.s.x).toBe(pos.j.x);
    expect(pos.s.y).toBeLessThan(pos.j.y);
  });

  it("places new blocks clear of those the layout places, and moves none of them", () => {
    const body = chainModel(3);
    body.layout = { g: { x: 0, y: 0 }, j0: { x: 120, y: 0 } };
    const want = body.components.map((c) => c.name).filter((n) => !body.layout[n]);
    const pos = layoutBlocks(body, want, {}, info);
    expect(Object.keys(pos).sort()).toEqual(want.sort());
    const all = { ...pos, g: body.layout.g, j0: body.layout.j0 };
    const rects = boxes(body, all);
    for (const n of want) {
      const r = rects.find((x) => x.id === n);
      for (const f of rects.filter((x) => x.id === "g" || x.id === "j0")) expect(r.x0 < f.x1 && f.x0 < r.x1 && r.y0 < f.y1 && f.y0 < r.y1).toBe(false);
    }
  });
});
