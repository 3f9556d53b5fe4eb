// The routing service: answers in the order asked, the latest request only while the worker
// is busy (a drag builds no backlog), answers held back and delivered on release, and the
// same routes through a worker-like port as from the router itself.
import { describe, expect, it } from "vitest";
import { RouteService, answer } from "../src/studio/routeservice.js";
import { WireRouter, routeWires } from "../src/studio/routing.js";

const rects = [
  { id: "a", x0: 0, y0: 0, x1: 100, y1: 60 },
  { id: "b", x0: 300, y0: 120, x1: 400, y1: 180 },
];
const wires = [{ id: "w", net: 0, a: { x: 107, y: 30, dir: [1, 0] }, b: { x: 293, y: 150, dir: [-1, 0] } }];

/** A stand-in for a worker: messages kept until ``flush`` answers them with a real router. */
function fakeWorker() {
  const router = new WireRouter();
  const port = { sent: [], onmessage: null, postMessage: (m) => port.sent.push(m) };
  port.flush = () => {
    const m = port.sent.shift();
    port.onmessage({ data: answer(router, m, "worker") });
  };
  return port;
}

describe("RouteService", () => {
  it("routes at once where there is no worker", () => {
    const got = [];
    const s = new RouteService(null, (r) => got.push(r));
    s.request(rects, wires);
    expect(got).toHaveLength(1);
    expect(got[0].where).toBe("page");
    expect(got[0].wires.get("w").points).toEqual(routeWires(rects, wires).wires.get("w").points);
    expect(s.pending).toBe(false);
  });

  it("sends only the latest request while the worker is busy", () => {
    const port = fakeWorker();
    const got = [];
    const s = new RouteService(port, (r) => got.push(r));
    s.request(rects, wires);
    const moved = rects.map((r) => (r.id === "b" ? { ...r, y0: r.y0 + 40, y1: r.y1 + 40 } : r));
    const w2 = [{ ...wires[0], b: { ...wires[0].b, y: 190 } }];
    for (let k = 0; k < 5; k++) s.request(moved, w2);
    s.request(rects, wires);
    s.request(moved, w2);
    expect(port.sent.map((m) => m.seq)).toEqual([1]);
    expect(s.pending).toBe(true);
    port.flush();
    expect(port.sent.map((m) => m.seq)).toEqual([4]);
    port.flush();
    expect(got.map((r) => r.seq)).toEqual([1, 4]);
    expect(got[1].where).toBe("worker");
    const pts = got[1].wires.get("w").points;
    expect(pts[pts.length - 1]).toEqual({ x: 293, y: 190 });
    expect(s.pending).toBe(false);
  });

  it("does not ask again for the diagram last asked about", () => {
    const port = fakeWorker();
    const got = [];
    const s = new RouteService(port, (r) => got.push(r));
    s.request(rects, wires);
    port.flush();
    // a re-render with the same places: equal, not the same, arrays
    s.request(rects.map((r) => ({ ...r })), wires.map((w) => ({ ...w })));
    expect(port.sent).toHaveLength(0);
    expect(s.pending).toBe(false);
    const moved = rects.map((r) => (r.id === "b" ? { ...r, x0: r.x0 + 20, x1: r.x1 + 20 } : r));
    s.request(moved, wires);
    expect(port.sent.map((m) => m.seq)).toEqual([2]);
    port.flush();
    // and back where it was: a new request (the last asked was the moved diagram)
    s.request(rects, wires);
    expect(port.sent.map((m) => m.seq)).toEqual([3]);
    port.flush();
    expect(got.map((r) => r.seq)).toEqual([1, 2, 3]);
  });

  it("holds answers back until released", () => {
    const port = fakeWorker();
    const got = [];
    const s = new RouteService(port, (r) => got.push(r));
    s.hold(true);
    s.request(rects, wires);
    port.flush();
    expect(got).toHaveLength(0);
    expect(s.pending).toBe(true);
    s.hold(false);
    expect(got.map((r) => r.seq)).toEqual([1]);
    expect(s.pending).toBe(false);
  });
});
