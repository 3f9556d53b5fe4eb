// The document model of the studio: a model file's top-level object (format
// "kinetwork.model", version 1 or 2), edited immutably; scopes (the model itself, or one of
// its subsystem definitions), the wiring rule of kn's Model.connect, names, layout.

export const DOMAIN_COLORS = {
  frame: "#5f5f5f",
  rotational: "#404040",
  translational: "#007f00",
  signal_in: "#00007f",
  signal_out: "#00007f",
  any: "#a15c00",
};

// layout units (as written in files) -> screen pixels of the diagram at zoom 1
export const SCALE = 1.5;
export const GRID = 15; // snap grid in pixels (10 layout units)

const SIGNALS = new Set(["signal_in", "signal_out"]);

/**
 * Why two ports cannot be wired, or null when they can: kn's Model.connect (same domain,
 * not twice) and, given ``domainOf``, the signal rule of its validation (one source a signal).
 * @param {{path: string, domain: string}} a
 * @param {{path: string, domain: string}} b
 * @param {string[][]} connections
 * @param {(path: string) => string | null} [domainOf]
 */
export function connectProblem(a, b, connections, domainOf) {
  if (a.path === b.path) return `cannot connect ${a.path} to itself`;
  const da = a.domain;
  const db = b.domain;
  const signals = SIGNALS.has(da) && SIGNALS.has(db);
  if (da !== db && da !== "any" && db !== "any" && !signals) {
    return `cannot connect ${a.path} (${da}) to ${b.path} (${db}): ports of different domains`;
  }
  for (const [x, y] of connections || []) {
    if ((x === a.path && y === b.path) || (x === b.path && y === a.path)) {
      return `${a.path} and ${b.path} are already connected`;
    }
  }
  if (signals && domainOf) return signalSourceProblem(a.path, b.path, connections, domainOf);
  return null;
}

/** The ports wired together with ``path`` (its connection set), ``path`` included. */
export function connectedSet(path, connections) {
  const seen = new Set([path]);
  const todo = [path];
  while (todo.length) {
    const p = todo.pop();
    for (const [x, y] of connections || []) {
      const other = x === p ? y : y === p ? x : null;
      if (other !== null && !seen.has(other)) {
        seen.add(other);
        todo.push(other);
      }
    }
  }
  return seen;
}

/**
 * Why wiring signal ports ``a`` and ``b`` would give a signal two sources (kn's rule: a
 * signal connection set has exactly one output), or null.
 * @param {(path: string) => string | null} domainOf
 */
export function signalSourceProblem(a, b, connections, domainOf) {
  const outsOf = (p) => [...connectedSet(p, connections)].filter((q) => domainOf(q) === "signal_out");
  const outA = outsOf(a);
  const outB = outsOf(b);
  if (!outA.length || !outB.length) return null;
  if (domainOf(a) === "signal_out" && domainOf(b) === "signal_out") {
    return `cannot connect ${a} to ${b}: both are signal outputs, and a signal has exactly one source`;
  }
  const [inPort, fed, other] = domainOf(a) === "signal_out" ? [b, outB[0], a] : [a, outA[0], b];
  return `cannot connect ${other} to ${inPort}: ${inPort} is fed by ${fed} already, and a signal has exactly one source`;
}

/** Which side of a block a port sits on: left, right, top or bottom. */
export function portSide(portName, domain, ports) {
  if (/_a$/.test(portName) || domain === "signal_in") return "left";
  if (/_b$/.test(portName) || domain === "signal_out") return "right";
  // a joint's drive flanges: support above, axis below (where its probe usually hangs)
  if (/^support/.test(portName)) return "top";
  if (/^axis/.test(portName)) return "bottom";
  if (portName === "port") return "top";
  if (portName === "frame") return "right";
  if (portName === "flange") {
    // a sensor reads its flange (left) and puts out y (right); a source drives it (right)
    const hasOut = (ports || []).some((p) => p.domain === "signal_out");
    return hasOut ? "left" : "right";
  }
  return "top";
}

const SHORT = {
  RigidBody: "mass",
  FixedTranslation: "link",
  FixedRotation: "rotation",
  SpringDamper: "spring",
  BodyBox: "box",
  BodyCylinder: "cylinder",
  BodySphere: "sphere",
};

/** The stem of fresh names of a type: "multibody.Revolute" -> "revolute". */
export function nameStem(type) {
  const cls = String(type).split(".").pop();
  if (SHORT[cls]) return SHORT[cls];
  const stem = cls.charAt(0).toLowerCase() + cls.slice(1);
  return /^[A-Za-z_][A-Za-z0-9_]*$/.test(stem) ? stem : "part";
}

/** The first of stem1, stem2, ... not in ``taken`` (a Set). */
export function freshName(stem, taken) {
  const base = stem.replace(/\d+$/, "") || "part";
  for (let i = 1; ; i++) {
    const name = `${base}${i}`;
    if (!taken.has(name)) return name;
  }
}

export const IDENT = /^[A-Za-z_][A-Za-z0-9_]*$/;

export function clone(x) {
  return x === undefined ? undefined : JSON.parse(JSON.stringify(x));
}

/** A new, empty model. */
export function emptyModel(name = "untitled") {
  return {
    format: "kinetwork.model",
    version: 1,
    name,
    description: "",
    parameters: {},
    components: [],
    connections: [],
    simulation: { t_end: 10.0, n_points: 1001, method: "auto", rtol: 1e-8, atol: 1e-10 },
    layout: {},
  };
}

// -- paths ---------------------------------------------------------------------------------

export function dirname(path) {
  if (!path) return "";
  const i = path.lastIndexOf("/");
  return i < 0 ? "" : path.slice(0, i);
}

export function joinPath(folder, rel) {
  const parts = (folder ? folder.split("/") : []).concat(rel.split("/"));
  const out = [];
  for (const p of parts) {
    if (p === "" || p === ".") continue;
    if (p === "..") out.pop();
    else out.push(p);
  }
  return out.join("/");
}

export function relPath(from, to) {
  const a = from ? from.split("/") : [];
  const b = to.split("/");
  let i = 0;
  while (i < a.length && i < b.length - 1 && a[i] === b[i]) i++;
  return [...a.slice(i).map(() => ".."), ...b.slice(i)].join("/");
}

// -- scopes: the model, or one of its definitions -----------------------------------------

/**
 * Where the definition of subsystem type ``type`` is, as seen from the doc at ``docPath``:
 * {kind: "inline", body} | {kind: "file", key, folder} (key: the root-relative path of its
 * file, in the definition cache) | null (not a definition: a registry type or unknown).
 */
export function definitionSource(doc, docPath, type, palette, folderOverride) {
  if (!type || (palette && palette.types[type])) return null;
  if (!IDENT.test(type)) return null;
  const folder = folderOverride !== undefined ? folderOverride : dirname(docPath);
  const entry = doc.definitions && doc.definitions[type];
  if (entry && typeof entry === "object") {
    if (typeof entry.file === "string") {
      const key = joinPath(folder, entry.file);
      return { kind: "file", key, folder: dirname(key) };
    }
    return { kind: "inline", body: entry };
  }
  const key = joinPath(folder, `${type}.json`);
  return { kind: "file", key, folder: dirname(key), implicit: true };
}

/**
 * Resolve subsystem type ``type`` as seen from ``ctx`` ({palette, doc, docPath, defCache}):
 * {src, body, ctx: the context inside it} (body null while its file loads, or when it is
 * missing), or null for a registry type or a name that cannot be a definition.
 */
export function resolveDef(type, ctx) {
  const src = definitionSource(ctx.doc, ctx.docPath, type, ctx.palette);
  if (!src) return null;
  if (src.kind === "inline") return { src, body: src.body, ctx };
  const hit = ctx.defCache[src.key];
  if (!hit || hit.status !== "ok") return { src, body: null, ctx, missing: !!hit && hit.status === "missing" };
  return { src, body: hit.model, ctx: { ...ctx, doc: hit.model, docPath: src.key } };
}

/** The scope at the end of a chain of definition names, from the root: {body, ctx, res}. */
export function resolveScope(scopes, ctx) {
  let cur = { body: ctx.doc, ctx, res: null };
  for (const name of scopes) {
    const r = resolveDef(name, cur.ctx);
    if (!r || !r.body) return null;
    cur = { body: r.body, ctx: r.ctx, res: r };
  }
  return cur;
}

/**
 * The document with ``fn`` applied to the body of the scope at the end of ``scopes`` (the
 * model itself when there is none). Every definition on the way is made inline, so the edit
 * is the one used; the document is unchanged when a scope cannot be resolved.
 * @param {any} doc
 * @param {string[]} scopes
 * @param {{palette: any, docPath: string | null, defCache: any}} ctx
 * @param {(body: any) => any} fn
 */
export function editInScope(doc, scopes, ctx, fn) {
  if (!scopes.length) return fn(doc);
  let c = { ...ctx, doc };
  let out = doc;
  for (let i = 0; i < scopes.length; i++) {
    const r = resolveDef(scopes[i], c);
    if (!r || !r.body) return doc;
    if (i === scopes.length - 1) out = updateDefinition(out, ctx.docPath, scopes[i], r, fn);
    else if (r.src.kind === "file") out = updateDefinition(out, ctx.docPath, scopes[i], r, (x) => x);
    c = r.ctx;
  }
  return out;
}

const BODY_KEYS = ["description", "parameters", "ports", "components", "connections", "layout"];

/**
 * Replace the body of definition ``name`` (resolved as ``res``) by ``fn(body)``: it is
 * written inline in the model's definitions (as kn's writer does for a changed definition);
 * a definition read from a file brings its own definitions along, their file paths seen
 * from the model's folder.
 */
export function updateDefinition(doc, docPath, name, res, fn) {
  const body = {};
  for (const k of BODY_KEYS) if (res.body[k] !== undefined) body[k] = res.body[k];
  const defs = { ...(doc.definitions || {}) };
  if (res.src.kind === "file") {
    for (const [n, entry] of Object.entries(res.body.definitions || {})) {
      if (defs[n] || n === name) continue;
      defs[n] = entry && typeof entry.file === "string"
        ? { file: relPath(dirname(docPath), joinPath(res.src.folder, entry.file)) }
        : clone(entry);
    }
  }
  defs[name] = fn(clone(body));
  return orderKeys({ ...doc, version: 2, definitions: defs });
}

const KEY_ORDER = ["format", "version", "name", "description", "parameters", "ports", "components",
  "connections", "simulation", "layout", "definitions"];

export function orderKeys(doc) {
  const out = {};
  for (const k of KEY_ORDER) if (doc[k] !== undefined) out[k] = doc[k];
  for (const k of Object.keys(doc)) if (!(k in out)) out[k] = doc[k];
  return out;
}

// -- component and port information ---------------------------------------------------------

/**
 * TypeInfo of a component type: the palette's for a registry type, one made from the
 * definition for a subsystem ({subsystem: true, ports with their domains}), or null.
 */
export function typeInfo(type, ctx, depth = 0) {
  const { palette } = ctx;
  if (palette && palette.types[type]) return palette.types[type];
  if (depth > 16) return null;
  const r = resolveDef(type, ctx);
  if (!r || !r.body) return null;
  const body = r.body;
  const ports = Object.entries(body.ports || {}).map(([name, ref]) => ({
    name,
    domain: refDomain(body, ref, r.ctx, depth + 1),
    doc: `${ref} of ${type}`,
    optional: true,
    // on the side of the block its inner port is on (link1.frame_a: left)
    side: refSide(body, ref, r.ctx, depth + 1),
  }));
  const params = Object.entries(body.parameters || {}).map(([name, value]) => ({
    name,
    unit: "",
    default: value,
    min: null,
    max: null,
    shape: [],
    kind: "real",
    choices: null,
    doc: `parameter ${name} of ${type}`,
    required: false,
    time: false,
  }));
  return { type, doc: body.description || `subsystem ${type}`, ports, params, subsystem: true };
}

/** The side of its block that "comp.port" inside a body is drawn on, or undefined. */
function refSide(body, ref, ctx, depth) {
  if (typeof ref !== "string") return undefined;
  const [cname, pname] = ref.split(".");
  const comp = (body.components || []).find((c) => c.name === cname);
  const info = comp && typeInfo(comp.type, ctx, depth + 1);
  const port = info && info.ports.find((p) => p.name === pname);
  if (!port) return undefined;
  return port.side || portSide(pname, port.domain, info.ports);
}

/** The domain of "comp.port" inside a body. */
export function refDomain(body, ref, ctx, depth = 0) {
  if (typeof ref !== "string") return "any";
  const [cname, pname] = ref.split(".");
  const comp = (body.components || []).find((c) => c.name === cname);
  if (!comp) return "any";
  const info = typeInfo(comp.type, ctx, depth + 1);
  const port = info && info.ports.find((p) => p.name === pname);
  return port ? port.domain : "any";
}

/** The domain of port "comp.port" of the scope, or null when there is no such port. */
export function portDomain(body, path, ctx) {
  const [cname, pname] = path.split(".");
  const comp = (body.components || []).find((c) => c.name === cname);
  if (!comp) return null;
  const info = typeInfo(comp.type, ctx);
  const port = info && info.ports.find((p) => p.name === pname);
  return port ? port.domain : null;
}

// -- editing operations on a scope body -----------------------------------------------------

export function takenNames(body) {
  return new Set((body.components || []).map((c) => c.name));
}

export function addComponent(body, comp, pos) {
  const layout = { ...(body.layout || {}) };
  if (pos) layout[comp.name] = pos;
  return { ...body, components: [...(body.components || []), comp], layout };
}

export function removeComponents(body, names) {
  const gone = new Set(names);
  const layout = { ...(body.layout || {}) };
  for (const n of gone) delete layout[n];
  const ports = {};
  for (const [k, ref] of Object.entries(body.ports || {})) {
    if (!gone.has(String(ref).split(".")[0])) ports[k] = ref;
  }
  const out = {
    ...body,
    components: (body.components || []).filter((c) => !gone.has(c.name)),
    connections: (body.connections || []).filter(
      ([a, b]) => !gone.has(String(a).split(".")[0]) && !gone.has(String(b).split(".")[0]),
    ),
    layout,
  };
  if (body.ports) out.ports = ports;
  return out;
}

export function renameComponent(body, from, to) {
  const re = (ref) => {
    const [c, p] = String(ref).split(".");
    return c === from ? `${to}.${p}` : ref;
  };
  const layout = {};
  for (const [k, v] of Object.entries(body.layout || {})) layout[k === from ? to : k] = v;
  const out = {
    ...body,
    components: body.components.map((c) => (c.name === from ? { ...c, name: to } : c)),
    connections: (body.connections || []).map(([a, b]) => [re(a), re(b)]),
    layout,
  };
  if (body.ports) {
    out.ports = Object.fromEntries(Object.entries(body.ports).map(([k, v]) => [k, re(v)]));
  }
  return out;
}

export function setParam(body, cname, key, value) {
  return {
    ...body,
    components: body.components.map((c) => {
      if (c.name !== cname) return c;
      const params = { ...(c.params || {}) };
      if (value === undefined) delete params[key];
      else params[key] = value;
      return { ...c, params };
    }),
  };
}

/** The components named, moved by (dx, dy) layout units from where they are shown. */
export function moveComponents(body, names, dx, dy, positionOf) {
  const layout = { ...(body.layout || {}) };
  for (const n of names) {
    const p = positionOf(n);
    if (!p) continue;
    layout[n] = { ...(layout[n] || {}), x: Math.round(p.x + dx), y: Math.round(p.y + dy) };
  }
  return { ...body, layout };
}

/** Components placed at ``moved`` (name -> {x, y}), keeping the rest of their layout entry. */
export function placeComponents(body, moved) {
  const old = body.layout || {};
  const layout = { ...old };
  let changed = false;
  for (const [k, v] of Object.entries(moved)) {
    if (old[k] && old[k].x === v.x && old[k].y === v.y) continue;
    layout[k] = { ...(old[k] || {}), x: v.x, y: v.y };
    changed = true;
  }
  return changed ? { ...body, layout } : body;
}

/** A block turned a quarter to the right: ``layout[name].rotation`` 0, 90, 180 or 270. */
export function rotateComponent(body, name, positionOf) {
  const old = (body.layout || {})[name] || positionOf(name) || { x: 0, y: 0 };
  const rotation = (((old.rotation || 0) + 90) % 360 + 360) % 360;
  const entry = { ...old, rotation };
  if (!rotation) delete entry.rotation;
  return { ...body, layout: { ...(body.layout || {}), [name]: entry } };
}

/** A block mirrored left to right (``layout[name].flip``), or mirrored back. */
export function flipComponent(body, name, positionOf) {
  const old = (body.layout || {})[name] || positionOf(name) || { x: 0, y: 0 };
  const entry = { ...old, flip: !old.flip };
  if (!entry.flip) delete entry.flip;
  return { ...body, layout: { ...(body.layout || {}), [name]: entry } };
}

/**
 * The side a port is drawn on once its block is mirrored (``flip``: left and right change
 * places, in the block's own frame) and then turned by ``rotation`` degrees.
 */
export function placedSide(side, rotation, flip) {
  const mirrored = flip && (side === "left" || side === "right") ? (side === "left" ? "right" : "left") : side;
  return rotatedSide(mirrored, rotation);
}

/** The side a port is drawn on once its block is turned by ``rotation`` degrees. */
export function rotatedSide(side, rotation) {
  const order = ["left", "top", "right", "bottom"];
  const turns = Math.round(((rotation || 0) % 360 + 360) % 360 / 90);
  const i = order.indexOf(side);
  return i < 0 ? side : order[(i + turns) % 4];
}

/**
 * A copy of components (with the wires among them) renamed to fresh names of ``body``, their
 * top-left corner at ``at`` (layout units) or, without it, beside the originals, below them.
 * @returns {{body: any, names: string[]}}
 */
export function pasteComponents(body, clip, at) {
  const taken = takenNames(body);
  const rename = {};
  for (const c of clip.components) {
    const n = freshName(c.name, taken);
    taken.add(n);
    rename[c.name] = n;
  }
  const pts = clip.components.map((c) => clip.positions[c.name] || { x: 0, y: 0 });
  const minX = Math.min(...pts.map((p) => p.x));
  const minY = Math.min(...pts.map((p) => p.y));
  const maxY = Math.max(...pts.map((p) => p.y));
  const origin = at || { x: minX, y: maxY + 90 };
  const re = (ref) => {
    const [c, p] = String(ref).split(".");
    return `${rename[c]}.${p}`;
  };
  let next = body;
  clip.components.forEach((c, i) => {
    const p = { x: Math.round((origin.x + pts[i].x - minX) / 10) * 10, y: Math.round((origin.y + pts[i].y - minY) / 10) * 10 };
    const rotation = clip.rotations && clip.rotations[c.name];
    const flip = clip.flips && clip.flips[c.name];
    next = addComponent(next, { ...clone(c), name: rename[c.name] }, { ...p, ...(rotation ? { rotation } : {}), ...(flip ? { flip: true } : {}) });
  });
  next = { ...next, connections: [...(next.connections || []), ...clip.connections.map(([a, b]) => [re(a), re(b)])] };
  return { body: next, names: Object.values(rename) };
}

/**
 * Why the studio cannot show ``data`` as a diagram (its validation says the rest), or null:
 * the parts it draws must have their shape (lists of named components and of pairs).
 */
export function shapeProblem(data) {
  const isObj = (x) => x !== null && typeof x === "object" && !Array.isArray(x);
  if (!isObj(data)) return "the file does not hold a JSON object";
  const bodies = [["", data]];
  if (data.definitions !== undefined) {
    if (!isObj(data.definitions)) return "definitions: must be an object";
    for (const [k, v] of Object.entries(data.definitions)) {
      if (!isObj(v)) return `definitions.${k}: must be an object`;
      if (typeof v.file !== "string") bodies.push([`definitions.${k}.`, v]);
    }
  }
  for (const [where, b] of bodies) {
    if (b.components !== undefined) {
      if (!Array.isArray(b.components)) return `${where}components: must be a list`;
      for (const [i, c] of b.components.entries()) {
        if (!isObj(c) || typeof c.name !== "string" || typeof c.type !== "string") {
          return `${where}components[${i}]: must be an object with a name and a type`;
        }
        if (c.params !== undefined && !isObj(c.params)) return `${where}components[${i}] params: must be an object`;
      }
    }
    if (b.connections !== undefined) {
      if (!Array.isArray(b.connections)) return `${where}connections: must be a list`;
      for (const [i, c] of b.connections.entries()) {
        if (!Array.isArray(c) || c.length !== 2 || c.some((x) => typeof x !== "string")) {
          return `${where}connections[${i}]: must be a pair of "component.port"`;
        }
      }
    }
    for (const key of ["parameters", "layout", "ports"]) {
      if (b[key] !== undefined && !isObj(b[key])) return `${where}${key}: must be an object`;
    }
  }
  if (data.simulation !== undefined && !isObj(data.simulation)) return "simulation: must be an object";
  return null;
}
