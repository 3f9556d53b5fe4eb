// What the diagram shows of the scope: a block per component (its ports, position, turn and
// problems), a wire per connection coloured by domain, and inside a definition its exposed
// ports. Derived from the document only; the canvas adds what React Flow holds (drags, sizes).
import { useMemo } from "react";
import { MarkerType } from "@xyflow/react";
import { DOMAIN_COLORS, SCALE, portDomain, portSide, resolveDef, typeInfo } from "../model.js";
import { useStudio } from "../store.js";

/** A definition's exposed ports, each beside the inner port it stands for. */
export function exposedPorts(body, ctx, posOf, moved) {
  return Object.entries(body.ports || {}).map(([pname, ref]) => {
    const [cname, port] = String(ref).split(".");
    const comp = (body.components || []).find((c) => c.name === cname);
    const info = comp && typeInfo(comp.type, ctx);
    const pinfo = info && info.ports.find((p) => p.name === port);
    const domain = pinfo ? pinfo.domain : "any";
    const side = pinfo ? pinfo.side || portSide(port, domain, info.ports) : "left";
    const at = posOf(cname) || { x: 0, y: 0 };
    // above the block, on the side of its port (a row of blocks leaves no room beside)
    const shift = { left: [-50, -50], right: [70, -50], top: [20, -55], bottom: [20, 75] }[side];
    const pos = (moved && moved[`@${pname}`]) || { x: at.x + shift[0], y: at.y + shift[1] };
    return { pname, ref, cname, port, domain, side, pos };
  });
}

/**
 * @param {import("./useDefinitions.js").Scope} scope useScope()'s answer
 * @param {Map<string, any[]>} byBlock problems of the scope by block
 * @param {import("../problems.js").Place[]} here the problems of the scope
 */
export function useDiagram(scope, byBlock, here) {
  const { body, ctx, posOf, scopeKey } = scope;
  const inDefinition = useStudio((s) => s.scopes.length > 0);
  const moved = useStudio((s) => s.autoPos[scopeKey]);

  const exposed = useMemo(() => (inDefinition ? exposedPorts(body, ctx, posOf, moved) : []), [inDefinition, body, ctx, posOf, moved]);

  const nodes = useMemo(() => {
    const conns = body.connections || [];
    const blocks = (body.components || []).map((c) => {
      const info = typeInfo(c.type, ctx);
      const p = posOf(c.name) || { x: 0, y: 0 };
      let ports = null;
      if (!info) {
        // an unknown type: the ports its wires name
        const names = new Set();
        for (const [a, b] of conns) {
          for (const ref of [a, b]) {
            const [cn, pn] = String(ref).split(".");
            if (cn === c.name && pn) names.add(pn);
          }
        }
        ports = [...names].map((n) => ({ name: n, domain: "any" }));
      }
      const r = info ? null : resolveDef(c.type, ctx);
      return {
        id: c.name,
        type: "block",
        position: { x: p.x * SCALE, y: p.y * SCALE },
        data: {
          name: c.name,
          type: c.type,
          info,
          ports,
          rotation: (body.layout && body.layout[c.name] && body.layout[c.name].rotation) || 0,
          flip: !!(body.layout && body.layout[c.name] && body.layout[c.name].flip),
          problems: byBlock.get(c.name) || [],
          subsystem: !!(info && info.subsystem),
          unknown: !info && !(r && !r.body && !r.missing),
        },
      };
    });
    const ports = exposed.map((e) => ({
      id: `@${e.pname}`,
      type: "extport",
      position: { x: e.pos.x * SCALE, y: e.pos.y * SCALE },
      data: { name: e.pname, domain: e.domain, side: e.side, ref: e.ref },
    }));
    return [...blocks, ...ports];
  }, [body, ctx, posOf, byBlock, exposed]);

  const edges = useMemo(() => {
    const badConn = new Set(here.filter((p) => p.connection !== null).map((p) => p.connection));
    const wires = (body.connections || []).map(([a, b], i) => {
      const [ca, pa] = String(a).split(".");
      const [cb, pb] = String(b).split(".");
      let dom = portDomain(body, a, ctx);
      if (!dom || dom === "any") dom = portDomain(body, b, ctx) || dom || "any";
      const bad = badConn.has(i);
      const color = bad ? "#e03131" : DOMAIN_COLORS[dom] || "#888";
      // a signal wire points at its input
      const arrow = { type: MarkerType.ArrowClosed, color, width: 14, height: 14 };
      let markers = {};
      if (dom === "signal_in" || dom === "signal_out") {
        if (portDomain(body, b, ctx) === "signal_in") markers = { markerEnd: arrow };
        else if (portDomain(body, a, ctx) === "signal_in") markers = { markerStart: arrow };
      }
      return {
        ...markers,
        id: `${a}~${b}~${i}`,
        source: ca,
        sourceHandle: pa,
        target: cb,
        targetHandle: pb,
        data: { a, b },
        className: `kn-edge kn-edge-${dom}${bad ? " bad" : ""}`,
        style: { stroke: color, strokeWidth: dom === "frame" ? 2.6 : 1.8, strokeDasharray: dom === "any" ? "5 3" : undefined },
      };
    });
    const links = exposed.map((e) => ({
      id: `@${e.pname}`,
      source: `@${e.pname}`,
      sourceHandle: "port",
      target: e.cname,
      targetHandle: e.port,
      data: { exposed: e.pname },
      className: "kn-edge kn-edge-exposed",
      style: { stroke: DOMAIN_COLORS[e.domain] || "#888", strokeWidth: 1.6, strokeDasharray: "6 4" },
    }));
    return [...wires, ...links];
  }, [body, ctx, here, exposed]);

  return { nodes, edges, exposed };
}
