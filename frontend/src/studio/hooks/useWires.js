// The wires of the diagram, routed (routing.js) from where the blocks are shown: their
// places in the document or, while the mouse drags, React Flow's. Each change routes again
// only the wires it concerns, in a web worker (routeservice.js): the page answers input
// meanwhile and draws each wire as last routed (a wire whose ends moved, as a plain elbow)
// until the new routes arrive.
import { useEffect, useMemo, useState } from "react";
import { OUTWARD, blockGeometry, portPoint } from "../geometry.js";
import { simplify } from "../routing.js";
import { RouteService, startWorker } from "../routeservice.js";
import { TESTING, trace } from "../testing.js";

const EXTPORT = { width: 90, height: 26 };
const FACING = { left: "right", right: "left", top: "bottom", bottom: "top" };

/** Net numbers of the ports ("comp.port") of ``edges``: wires joined at a port share a net. */
export function netsOf(edges) {
  const parent = new Map();
  const find = (p) => {
    if (!parent.has(p)) parent.set(p, p);
    let r = p;
    while (parent.get(r) !== r) r = parent.get(r);
    parent.set(p, r);
    return r;
  };
  for (const e of edges) parent.set(find(`${e.source}.${e.sourceHandle}`), find(`${e.target}.${e.targetHandle}`));
  const number = new Map();
  const net = new Map();
  for (const e of edges) {
    const root = find(`${e.source}.${e.sourceHandle}`);
    if (!number.has(root)) number.set(root, number.size);
    net.set(e.id, number.get(root));
  }
  return net;
}

/** Each node's rectangle and its ports' wire ends, in diagram pixels. */
export function shapes(nodes) {
  const out = new Map();
  for (const n of nodes) {
    const { x, y } = n.position;
    if (n.type === "extport") {
      const w = (n.measured && n.measured.width) || EXTPORT.width;
      const h = (n.measured && n.measured.height) || EXTPORT.height;
      const side = FACING[n.data.side] || "right";
      const handle = { side, x: side === "left" ? 0 : side === "right" ? w : w / 2, y: side === "top" ? 0 : side === "bottom" ? h : h / 2 };
      out.set(n.id, { rect: { id: n.id, x0: x, y0: y, x1: x + w, y1: y + h }, ports: new Map([["port", portPoint(x, y, handle)]]) });
      continue;
    }
    const ports = n.data.info ? n.data.info.ports : n.data.ports || [];
    const g = blockGeometry(ports, n.data.rotation, n.data.flip);
    out.set(n.id, {
      rect: { id: n.id, x0: x, y0: y, x1: x + g.width, y1: y + g.height },
      ports: new Map(g.handles.map((h) => [h.port.name, portPoint(x, y, h)])),
    });
  }
  return out;
}

function endOf(shape, port, other) {
  const p = shape && shape.ports.get(port);
  if (p) return p;
  // a wire to a port the block does not have (a type unknown, a definition loading): from
  // the middle of its side facing the other end
  const r = shape ? shape.rect : { x0: 0, y0: 0, x1: 0, y1: 0 };
  const side = other && other.x < r.x0 ? "left" : "right";
  return { x: side === "left" ? r.x0 - 7 : r.x1 + 7, y: Math.round((r.y0 + r.y1) / 2), dir: OUTWARD[side] };
}

/** Whether the route ``points`` still joins ends ``a`` and ``b``. */
function joins(points, a, b) {
  const p = points[0];
  const q = points[points.length - 1];
  return p.x === a.x && p.y === a.y && q.x === b.x && q.y === b.y;
}

/**
 * The edges with their routes in ``data.points``.
 * @param {any[]} nodes as shown (dragged positions, measured sizes)
 * @param {any[]} edges
 * @param {boolean} [placed] every block has its place: until then (blocks the layout has not
 *   yet placed stand at the origin) nothing is routed, as a pile of blocks at one point is
 *   the slowest diagram to route (1.7 s of arm_computed_torque's opening went there)
 * @param {(edges: any[]) => void} [onRouted] called with the edges once the routes of the
 *   diagram as shown are drawn (no routing outstanding)
 */
export function useWires(nodes, edges, placed = true, onRouted = undefined) {
  const [routes, setRoutes] = useState(() => /** @type {any} */ ({ seq: 0, wires: new Map(), routed: 0, ms: 0, where: null }));
  const [service] = useState(() => new RouteService(startWorker(), (r) => setRoutes(r)));
  useEffect(() => () => service.stop(), [service]);
  const asked = useMemo(() => {
    const shape = shapes(nodes);
    const nets = netsOf(edges);
    const wires = edges.map((e) => {
      const sa = shape.get(e.source);
      const sb = shape.get(e.target);
      const a = endOf(sa, e.sourceHandle, sb && sb.rect);
      const b = endOf(sb, e.targetHandle, sa && sa.rect);
      return { id: e.id, net: nets.get(e.id), a, b };
    });
    return { rects: [...shape.values()].map((s) => s.rect), wires };
  }, [nodes, edges]);
  useEffect(() => {
    if (placed) service.request(asked.rects, asked.wires);
  }, [service, asked, placed]);
  const out = useMemo(() => {
    const ends = new Map(asked.wires.map((w) => [w.id, w]));
    return edges.map((e) => {
      const w = ends.get(e.id);
      const old = routes.wires.get(e.id);
      const points = old && joins(old.points, w.a, w.b) ? old.points : simplify([w.a, { x: w.b.x, y: w.a.y }, w.b]);
      return { ...e, type: "wire", data: { ...e.data, points } };
    });
  }, [edges, asked, routes]);
  useEffect(() => {
    if (!TESTING) return;
    trace.wires = { rects: asked.rects, wires: asked.wires, routed: routes.routed, ms: routes.ms, where: routes.where, asked: service.seq, answered: routes.seq };
    trace.routing = service;
  }, [asked, routes, service]);
  useEffect(() => {
    if (onRouted && routes.seq > 0 && routes.seq === service.seq && !service.pending) onRouted(out);
  }, [routes, out, service, onRouted]);
  return out;
}
