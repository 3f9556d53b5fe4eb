// Folding a repeated pattern into subsystems, as a person draws a long chain: the link (a
// joint, its body and the translation to the next joint) becomes one definition, and the
// chain a row of its instances, wired link to link. The model means the same: every inner
// wire is the definition's, every wire between links or to the rest goes through its ports,
// and a value that differs between the links (a joint's initial angle) is a parameter of
// the definition given by each instance.
import { clone, IDENT } from "./model.js";
import { identifiers } from "./values.js";

/** Fewest repeats worth folding, and the longest pattern looked for (blocks). */
export const MIN_REPEATS = 3;
const MAX_PERIOD = 8;

const cname = (ref) => String(ref).split(".")[0];
const pname = (ref) => String(ref).split(".").slice(1).join(".");

/** A name made an identifier, distinct from ``taken`` (added to it). */
function fresh(stem, taken) {
  let base = stem.replace(/[^A-Za-z0-9_]/g, "_");
  if (!IDENT.test(base)) base = `p_${base}`;
  let name = base;
  for (let i = 2; taken.has(name); i++) name = `${base}${i}`;
  taken.add(name);
  return name;
}

/**
 * The values of one parameter across the units, as the definition holds it: the value itself
 * where all agree, a definition parameter per number that differs (a vector's differing
 * elements one by one); null when they differ otherwise (an expression, a matrix).
 */
function shared(values, stem, taken) {
  const same = values.every((v) => JSON.stringify(v) === JSON.stringify(values[0]));
  if (same) return { value: clone(values[0]), params: [] };
  const num = (v) => typeof v === "number" && Number.isFinite(v);
  if (values.every(num)) {
    const p = fresh(stem, taken);
    return { value: p, params: [[p, values]] };
  }
  const n = Array.isArray(values[0]) ? values[0].length : -1;
  if (n < 0 || !values.every((v) => Array.isArray(v) && v.length === n)) return null;
  const value = [];
  const params = [];
  for (let i = 0; i < n; i++) {
    const col = values.map((v) => v[i]);
    if (col.every((x) => JSON.stringify(x) === JSON.stringify(col[0]))) value.push(clone(col[0]));
    else if (col.every(num)) {
      const p = fresh(`${stem}_${i + 1}`, taken);
      value.push(p);
      params.push([p, col]);
    } else return null;
  }
  return { value, params };
}

/**
 * The plan of a fold of ``n`` units of ``p`` components from index ``s``, or null when the
 * units are not alike (other inner wiring, other wiring to their neighbours, a wire that
 * skips a unit, values that cannot be parameters).
 */
function plan(body, s, p, n) {
  const comps = body.components || [];
  const at = new Map(comps.map((c, i) => [c.name, i >= s && i < s + n * p ? [Math.floor((i - s) / p), (i - s) % p] : null]));
  const inner = Array.from({ length: n }, () => []);
  const between = Array.from({ length: Math.max(0, n - 1) }, () => []);
  const crossing = new Set(); // "local.port" wired outside the units
  for (const [a, b] of body.connections || []) {
    const ua = at.get(cname(a));
    const ub = at.get(cname(b));
    if (!ua && !ub) continue;
    if (ua && ub && ua[0] === ub[0]) inner[ua[0]].push(`${ua[1]}.${pname(a)}~${ub[1]}.${pname(b)}`);
    else if (ua && ub && Math.abs(ua[0] - ub[0]) === 1) {
      const lower = ua[0] < ub[0];
      between[Math.min(ua[0], ub[0])].push(`${lower ? ">" : "<"}${ua[1]}.${pname(a)}~${ub[1]}.${pname(b)}`);
    } else if (ua && ub) return null;
    else crossing.add(ua ? `${ua[1]}.${pname(a)}` : `${ub[1]}.${pname(b)}`);
  }
  for (const ref of Object.values(body.ports || {})) {
    const u = at.get(cname(ref));
    if (u) crossing.add(`${u[1]}.${pname(ref)}`);
  }
  const sig = (list) => JSON.stringify([...list].sort());
  if (inner.some((l) => sig(l) !== sig(inner[0]))) return null;
  if (between.some((l) => sig(l) !== sig(between[0]))) return null;

  const units = Array.from({ length: n }, (_, k) => comps.slice(s + k * p, s + (k + 1) * p));
  // the inner names: the first unit's without the number its unit shares (j0, b0 -> j, b)
  const suffix = (k) => {
    const m = units[k].map((c) => /(\d+)$/.exec(c.name));
    return m.every((x) => x && x[1] === m[0][1]) ? m[0][1] : null;
  };
  const tags = units.map((_, k) => suffix(k));
  const numbered = tags.every((t) => t !== null) && new Set(tags).size === n;
  let local = units[0].map((c) => (numbered ? c.name.slice(0, -tags[0].length) : c.name));
  if (new Set(local).size !== p || !local.every((x) => IDENT.test(x))) local = units[0].map((c) => c.name);

  // the definition's parameters: the outer ones the units use, then one per differing value
  const used = new Set();
  for (const u of units) for (const c of u) identifiers(Object.values(c.params || {}), used);
  const outer = body.parameters || {};
  const taken = new Set([...Object.keys(outer), ...local]);
  const parameters = {};
  const given = Array.from({ length: n }, () => ({}));
  for (const q of Object.keys(outer)) {
    if (!used.has(q)) continue;
    parameters[q] = clone(outer[q]);
    given.forEach((g) => (g[q] = q));
  }
  const inside = [];
  for (let i = 0; i < p; i++) {
    const keys = [...new Set(units.flatMap((u) => Object.keys(u[i].params || {})))];
    const params = {};
    for (const key of keys) {
      const values = units.map((u) => (u[i].params || {})[key]);
      if (values.some((v) => v === undefined) && !values.every((v) => v === undefined)) return null;
      const got = shared(values, `${local[i]}_${key}`, taken);
      if (!got) return null;
      params[key] = got.value;
      for (const [q, vals] of got.params) {
        parameters[q] = vals[0];
        vals.forEach((v, k) => (given[k][q] = v));
      }
    }
    const rest = clone(units[0][i]);
    delete rest.name;
    delete rest.params;
    inside.push({ name: local[i], ...rest, params });
  }
  // ports: each inner port wired across a unit's edge, named as it (j.frame_a -> frame_a,
  // as MSL's links), or after its block too where two blocks' ports have one name
  const refs = new Set(crossing);
  for (const e of between[0] || []) for (const end of e.slice(1).split("~")) refs.add(end);
  const sorted = [...refs].sort();
  const bare = sorted.map((r) => pname(r).replace(/\./g, "_"));
  const portTaken = new Set();
  const portOf = new Map();
  sorted.forEach((r, k) => {
    const alone = bare.filter((b) => b === bare[k]).length === 1;
    portOf.set(r, fresh(alone ? bare[k] : `${local[Number(r.split(".")[0])]}_${bare[k]}`, portTaken));
  });
  const ports = Object.fromEntries([...portOf].map(([r, name]) => [name, `${local[Number(r.split(".")[0])]}.${pname(r)}`]));
  const connections = inner[0].map((e) => e.split("~").map((end) => `${local[Number(end.split(".")[0])]}.${pname(end)}`));
  return { s, p, n, units, tags: numbered ? tags : null, at, portOf, parameters, given, definition: { inside, ports, connections } };
}

/** Which of two folds a person would make: more blocks folded, then fewer wires cut (ports). */
function better(a, b) {
  if (!b) return true;
  if (a.n * a.p !== b.n * b.p) return a.n * a.p > b.n * b.p;
  const pa = Object.keys(a.definition.ports).length;
  const pb = Object.keys(b.definition.ports).length;
  return pa !== pb ? pa < pb : !!a.tags && !b.tags;
}

/**
 * The longest repeated pattern of ``body`` worth folding (at least ``MIN_REPEATS`` alike
 * units of two or more blocks, in the file's order, cut where the fewest wires cross), or
 * null.
 * @param {any} body a model or a definition
 */
export function findRepeat(body) {
  const comps = body.components || [];
  const N = comps.length;
  let best = null;
  for (let p = 2; p <= MAX_PERIOD; p++) {
    for (let s = 0; s + p * MIN_REPEATS <= N; s++) {
      const alike = (k) => comps.slice(s + k * p, s + (k + 1) * p).every((c, i) => c.type === comps[s + i].type);
      let n = 1;
      while (s + (n + 1) * p <= N && alike(n)) n++;
      // a unit that differs ends the run: the run shortened from its end a few times (its
      // last unit wired to something else), no more (the work stays linear in the model)
      for (let tries = 0; tries < 3 && n >= MIN_REPEATS && (!best || n * p >= best.n * best.p); tries++, n--) {
        const found = plan(body, s, p, n);
        if (found) {
          if (better(found, best)) best = found;
          break;
        }
      }
    }
  }
  return best;
}

/**
 * ``body`` with the units of ``found`` (``findRepeat``) replaced by instances of a new
 * definition ``defName``.
 * @returns {{body: any, definition: any, instances: string[]}}
 */
export function foldRepeat(body, found, defName) {
  const { s, p, n, units, tags, at, portOf, parameters, given } = found;
  const stem = defName.charAt(0).toLowerCase() + defName.slice(1);
  const folded = new Set(units.flat().map((c) => c.name));
  const others = new Set((body.components || []).filter((c) => !folded.has(c.name)).map((c) => c.name));
  const names = units.map((_, k) => fresh(`${stem}${tags ? tags[k] : k + 1}`, others));
  const outside = (ref) => {
    const u = at.get(cname(ref));
    return u ? `${names[u[0]]}.${portOf.get(`${u[1]}.${pname(ref)}`)}` : ref;
  };
  const connections = [];
  for (const [a, b] of body.connections || []) {
    const ua = at.get(cname(a));
    const ub = at.get(cname(b));
    if (ua && ub && ua[0] === ub[0]) continue;
    connections.push([outside(a), outside(b)]);
  }
  const comps = [...(body.components || [])];
  comps.splice(s, n * p, ...names.map((name, k) => ({ name, type: defName, params: given[k] })));
  const layout = Object.fromEntries(Object.entries(body.layout || {}).filter(([k]) => !folded.has(k)));
  const out = { ...body, components: comps, connections, layout };
  if (body.ports) out.ports = Object.fromEntries(Object.entries(body.ports).map(([k, r]) => [k, outside(r)]));
  const { inside, ports, connections: innerWires } = found.definition;
  const definition = {
    description: `One of ${n} alike units (${inside.map((c) => c.name).join(", ")}), folded from ${units[0].map((c) => c.name).join(", ")} ... ${units[n - 1].map((c) => c.name).join(", ")}.`,
    parameters,
    ports,
    components: inside,
    connections: innerWires,
    layout: {},
  };
  return { body: out, definition, instances: names };
}
