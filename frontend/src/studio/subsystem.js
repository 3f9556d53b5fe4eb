// "Make subsystem": selected components of a scope become a new definition, placed once
// where they were, with a port exposed for each of their ports wired across the selection.
import { clone, freshName, IDENT } from "./model.js";
import { identifiers } from "./values.js";

/**
 * @param {any} body the scope's body (components, connections, layout, parameters)
 * @param {string[]} names the selected component names
 * @param {string} defName the new definition's name (its type in the file)
 * @param {string} instName the instance's name
 * @param {Record<string, {x: number, y: number}>} positions name -> {x, y} (layout units) of every component as shown
 * @returns {{body: any, definition: any}} the scope with the instance in place of the
 *   selection, and the definition's inline body.
 */
export function makeSubsystem(body, names, defName, instName, positions) {
  const inside = new Set(names);
  const comps = body.components || [];
  const chosen = comps.filter((c) => inside.has(c.name));
  const cname = (ref) => String(ref).split(".")[0];

  // parameters of the scope the selection uses: the definition's, fed by the outer ones
  const used = new Set();
  for (const c of chosen) identifiers(Object.values(c.params || {}), used);
  const outerParams = body.parameters || {};
  const parameters = {};
  const given = {};
  for (const p of Object.keys(outerParams)) {
    if (used.has(p)) {
      parameters[p] = clone(outerParams[p]);
      given[p] = p;
    }
  }

  // ports for the wires that cross the selection: one per inner port
  const ports = {};
  const portOf = new Map();
  const taken = new Set();
  const innerConnections = [];
  const outerConnections = [];
  for (const [a, b] of body.connections || []) {
    const ia = inside.has(cname(a));
    const ib = inside.has(cname(b));
    if (ia && ib) innerConnections.push([a, b]);
    else if (!ia && !ib) outerConnections.push([a, b]);
    else {
      const inner = ia ? a : b;
      const outer = ia ? b : a;
      if (!portOf.has(inner)) {
        let pname = inner.replace(".", "_");
        if (!IDENT.test(pname)) pname = "port";
        if (taken.has(pname)) pname = freshName(pname, taken);
        taken.add(pname);
        portOf.set(inner, pname);
        ports[pname] = inner;
      }
      outerConnections.push([outer, `${instName}.${portOf.get(inner)}`]);
    }
  }

  // the definition's layout: the selection's positions, moved to start at the origin
  const pts = chosen.map((c) => positions[c.name] || { x: 0, y: 0 });
  const minX = Math.min(...pts.map((p) => p.x));
  const minY = Math.min(...pts.map((p) => p.y));
  const layout = {};
  chosen.forEach((c, i) => {
    layout[c.name] = { x: pts[i].x - minX, y: pts[i].y - minY };
  });
  const cx = pts.reduce((s, p) => s + p.x, 0) / pts.length;
  const cy = pts.reduce((s, p) => s + p.y, 0) / pts.length;

  const definition = {
    description: `Made of ${chosen.map((c) => c.name).join(", ")}.`,
    parameters,
    ports,
    components: clone(chosen),
    connections: innerConnections,
    layout,
  };
  // the scope's layout: unchanged for the rest, the instance at the selection's centre
  const outerLayout = {};
  for (const [k, v] of Object.entries(body.layout || {})) if (!inside.has(k)) outerLayout[k] = v;
  outerLayout[instName] = { x: Math.round(cx / 10) * 10, y: Math.round(cy / 10) * 10 };

  const firstIndex = comps.findIndex((c) => inside.has(c.name));
  const rest = comps.filter((c) => !inside.has(c.name));
  rest.splice(Math.max(0, firstIndex), 0, { name: instName, type: defName, params: given });
  const nextBody = { ...body, components: rest, connections: outerConnections, layout: outerLayout };
  if (body.ports) {
    // a port the scope exposes from inside the selection now goes through the instance
    const scopePorts = {};
    for (const [k, ref] of Object.entries(body.ports)) {
      if (!inside.has(cname(ref))) scopePorts[k] = ref;
      else {
        if (!portOf.has(ref)) {
          let pname = ref.replace(".", "_");
          if (taken.has(pname)) pname = freshName(pname, taken);
          taken.add(pname);
          portOf.set(ref, pname);
          ports[pname] = ref;
        }
        scopePorts[k] = `${instName}.${portOf.get(ref)}`;
      }
    }
    nextBody.ports = scopePorts;
  }
  return { body: nextBody, definition };
}
