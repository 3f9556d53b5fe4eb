// Every edit of the diagram and the panels, each one step of the undo history: place, wire,
// move (mouse or arrow keys), delete, rename, duplicate, rotate, flip, copy and paste (at the
// pointer), parameters, make subsystem, open a subsystem.
import { useCallback, useMemo } from "react";
import { useReactFlow } from "@xyflow/react";
import {
  IDENT,
  SCALE,
  addComponent,
  clone,
  connectProblem,
  editInScope,
  freshName,
  moveComponents,
  nameStem,
  orderKeys,
  pasteComponents,
  placeComponents,
  portDomain,
  removeComponents,
  renameComponent,
  resolveDef,
  rotateComponent,
  flipComponent,
  setParam,
  takenNames,
} from "../model.js";
import { findRepeat, foldRepeat } from "../fold.js";
import { makeSubsystem } from "../subsystem.js";
import { studio, useStudio } from "../store.js";
import { prompt } from "./useFiles.js";

/** The clipboard: components, the wires among them and their positions (layout units). */
let clipboard = null;

/** Layout units a press of an arrow key moves the selection (Shift: five times as far). */
export const NUDGE = 10;

/** @typedef {ReturnType<typeof useEditing>} Edit */

/**
 * @param {import("./useDefinitions.js").Scope} scope useScope()'s answer
 * @param {{pname: string}[]} exposed useDiagram()'s exposed ports
 */
export function useEditing(scope, exposed) {
  const { body, ctx, posOf, scopeKey } = scope;
  const flow = useReactFlow();
  const toast = useStudio((s) => s.toast);
  const editScope = useStudio((s) => s.editScope);
  const select = useStudio((s) => s.select);

  const domainOf = useCallback(
    (path) => {
      if (path.startsWith("@")) return exposed.some((x) => `@${x.pname}.port` === path) ? "any" : null;
      return portDomain(body, path, ctx);
    },
    [body, ctx, exposed],
  );

  const checkConnection = useCallback(
    (a, b) => {
      if (a.startsWith("@") && b.startsWith("@")) return "two exposed ports cannot be wired to each other";
      const da = domainOf(a);
      const db = domainOf(b);
      if (!da || !db) return `no port ${!da ? a : b}`;
      return connectProblem({ path: a, domain: da }, { path: b, domain: db }, body.connections, domainOf);
    },
    [body, domainOf],
  );

  const connect = useCallback(
    (a, b) => {
      const why = checkConnection(a, b);
      if (why) {
        toast(why);
        return;
      }
      const ext = a.startsWith("@") ? [a, b] : b.startsWith("@") ? [b, a] : null;
      if (ext) {
        // wiring an exposed port to an inner port: it now stands for that one
        const pname = ext[0].slice(1, -".port".length);
        editScope((s) => ({ ...s, ports: { ...(s.ports || {}), [pname]: ext[1] } }));
        return;
      }
      editScope((s) => ({ ...s, connections: [...(s.connections || []), [a, b]] }));
    },
    [checkConnection, editScope, toast],
  );

  const moved = useCallback(
    (to) => {
      const ports = Object.fromEntries(Object.entries(to).filter(([k]) => k.startsWith("@")));
      if (Object.keys(ports).length) studio().setAutoPos(scopeKey, ports);
      const blocks = Object.fromEntries(Object.entries(to).filter(([k]) => !k.startsWith("@")));
      if (Object.keys(blocks).length) editScope((s) => placeComponents(s, blocks));
    },
    [editScope, scopeKey],
  );

  const nudge = useCallback(
    (dx, dy) => {
      const names = studio().selection.filter((n) => !n.startsWith("@"));
      if (!names.length) return;
      editScope((s) => moveComponents(s, names, dx, dy, posOf), `nudge:${scopeKey}:${names.join(",")}`);
    },
    [editScope, posOf, scopeKey],
  );

  const remove = useCallback(
    (names, edges) => {
      const unexpose = new Set([
        ...names.filter((n) => n.startsWith("@")).map((n) => n.slice(1)),
        ...edges.filter((e) => e && e.exposed).map((e) => e.exposed),
      ]);
      const gone = new Set(names.filter((n) => !n.startsWith("@")));
      const drop = new Set(edges.filter((e) => e && !e.exposed).map((e) => `${e.a}\u0000${e.b}`));
      if (!gone.size && !unexpose.size && !drop.size) return;
      editScope((s) => {
        let next = gone.size ? removeComponents(s, [...gone]) : s;
        if (unexpose.size) next = { ...next, ports: Object.fromEntries(Object.entries(next.ports || {}).filter(([k]) => !unexpose.has(k))) };
        if (drop.size) next = { ...next, connections: (next.connections || []).filter(([a, b]) => !drop.has(`${a}\u0000${b}`)) };
        return next;
      });
      select([]);
    },
    [editScope, select],
  );

  const removeSelected = useCallback(() => {
    const s = studio();
    const edges = s.selectedEdges.map((id) => edgeData(id)).filter(Boolean);
    if (s.selection.length || edges.length) remove(s.selection, edges);
  }, [remove]);

  const place = useCallback(
    (type, flowPos) => {
      const name = freshName(nameStem(type), takenNames(body));
      const pos = { x: Math.round(flowPos.x / SCALE / 10) * 10, y: Math.round(flowPos.y / SCALE / 10) * 10 };
      editScope((s) => addComponent(s, { name, type, params: {} }, pos));
      select([name]);
    },
    [body, editScope, select],
  );

  const placeAtCentre = useCallback(
    (type) => {
      const el = document.querySelector(".kn-canvas");
      const r = el ? el.getBoundingClientRect() : { left: 0, top: 0, width: 400, height: 300 };
      const p = flow.screenToFlowPosition({ x: r.left + r.width / 2, y: r.top + r.height / 2 });
      // a second block placed this way goes beside the first, not on it
      const taken = new Set((body.components || []).map((c) => posOf(c.name)).filter(Boolean).map((q) => `${Math.round(q.x / 30)}:${Math.round(q.y / 30)}`));
      let k = 0;
      let at = { x: p.x - 58, y: p.y - 32 };
      while (taken.has(`${Math.round(at.x / SCALE / 30)}:${Math.round(at.y / SCALE / 30)}`) && k < 20) {
        k++;
        at = { x: p.x - 58 + 45 * k, y: p.y - 32 + 45 * k };
      }
      place(type, at);
    },
    [flow, place, body, posOf],
  );

  const open = useCallback(
    (name) => {
      const comp = (body.components || []).find((c) => c.name === name);
      if (!comp) return;
      const r = resolveDef(comp.type, ctx);
      if (!r) return;
      if (!r.body) {
        toast(`the definition of ${comp.type} is ${r.missing ? "not found" : "still loading"}`);
        return;
      }
      studio().setScopes([...studio().scopes, comp.type]);
    },
    [body, ctx, toast],
  );

  const rename = useCallback(
    (from, to) => {
      if (to === from) return true;
      if (!IDENT.test(to)) {
        toast(`${JSON.stringify(to)} is not a component name: letters, digits and underscores, not starting with a digit`);
        return false;
      }
      if (takenNames(body).has(to)) {
        toast(`there is already a component named ${to}`);
        return false;
      }
      editScope((s) => renameComponent(s, from, to));
      select([to]);
      return true;
    },
    [body, editScope, select, toast],
  );

  const askRename = useCallback(
    async (name) => {
      const to = await prompt({ title: "Rename", label: `A new name for ${name}`, value: name, testid: "rename-to" });
      if (to !== null) rename(name, to.trim());
    },
    [rename],
  );

  const setParamOf = useCallback((cname, key, value) => editScope((s) => setParam(s, cname, key, value)), [editScope]);

  const setModelParam = useCallback(
    (name, value) =>
      editScope((s) => {
        const params = { ...(s.parameters || {}) };
        if (value === undefined) delete params[name];
        else params[name] = value;
        return orderKeys({ ...s, parameters: params });
      }),
    [editScope],
  );

  const renameModelParam = useCallback(
    (from, to) => {
      if (from === to) return;
      if (!IDENT.test(to)) {
        toast(`${JSON.stringify(to)} is not a parameter name`);
        return;
      }
      editScope((s) => {
        const params = {};
        for (const [k, v] of Object.entries(s.parameters || {})) params[k === from ? to : k] = v;
        return { ...s, parameters: params };
      });
    },
    [editScope, toast],
  );

  const setSim = useCallback(
    (key, value) =>
      studio().update((d) => {
        const sim = { ...(d.simulation || {}) };
        if (value === undefined) delete sim[key];
        else sim[key] = value;
        return orderKeys({ ...d, simulation: sim });
      }),
    [],
  );

  const setField = useCallback(
    (key, value) => {
      if (key === "name" && !studio().scopes.length) studio().update((d) => ({ ...d, name: value }));
      else editScope((s) => orderKeys({ ...s, [key]: value }));
    },
    [editScope],
  );

  const setPort = useCallback(
    (name, ref) =>
      editScope((s) => {
        const ports = { ...(s.ports || {}) };
        if (ref === undefined) delete ports[name];
        else ports[name] = ref;
        return { ...s, ports };
      }),
    [editScope],
  );

  const clip = useCallback(
    (names) => {
      const chosen = new Set(names);
      const comps = (body.components || []).filter((c) => chosen.has(c.name));
      if (!comps.length) return null;
      return {
        components: clone(comps),
        connections: (body.connections || []).filter(([a, b]) => chosen.has(a.split(".")[0]) && chosen.has(b.split(".")[0])),
        positions: Object.fromEntries(comps.map((c) => [c.name, posOf(c.name) || { x: 0, y: 0 }])),
        rotations: Object.fromEntries(comps.map((c) => [c.name, (body.layout && body.layout[c.name] && body.layout[c.name].rotation) || 0])),
        flips: Object.fromEntries(comps.map((c) => [c.name, !!(body.layout && body.layout[c.name] && body.layout[c.name].flip)])),
      };
    },
    [body, posOf],
  );

  const copy = useCallback(() => {
    const got = clip(studio().selection);
    if (!got) return;
    clipboard = got;
    toast(`copied ${got.components.length} component${got.components.length > 1 ? "s" : ""}`, "info");
  }, [clip, toast]);

  /** Paste the clipboard with its top-left block at ``at`` (layout units; default: the pointer). */
  const paste = useCallback(
    (at) => {
      if (!clipboard) return;
      const where = at || studio().pointer || null;
      let names = [];
      editScope((s) => {
        const out = pasteComponents(s, clipboard, where);
        names = out.names;
        return out.body;
      });
      select(names);
    },
    [editScope, select],
  );

  const duplicate = useCallback(
    (names) => {
      const got = clip(names);
      if (!got) return;
      let made = [];
      editScope((s) => {
        const out = pasteComponents(s, got, null);
        made = out.names;
        return out.body;
      });
      select(made);
    },
    [clip, editScope, select],
  );

  const rotate = useCallback(
    (names) => {
      const blocks = names.filter((n) => !n.startsWith("@"));
      if (blocks.length) editScope((s) => blocks.reduce((acc, n) => rotateComponent(acc, n, posOf), s));
    },
    [editScope, posOf],
  );

  const flip = useCallback(
    (names) => {
      const blocks = names.filter((n) => !n.startsWith("@"));
      if (blocks.length) editScope((s) => blocks.reduce((acc, n) => flipComponent(acc, n, posOf), s));
    },
    [editScope, posOf],
  );

  const selectAll = useCallback(() => select((body.components || []).map((c) => c.name)), [body, select]);

  const makeSub = useCallback(
    /** @param {string[]} [names] the blocks (default: the selection) */
    async (names) => {
      const chosen = (names || studio().selection).filter((n) => !n.startsWith("@"));
      if (!chosen.length) {
        toast("select the blocks to make a subsystem of (drag a box around them, or Ctrl+click)");
        return;
      }
      const { palette, hist } = studio();
      const taken = new Set([...Object.keys(hist.present.definitions || {}), ...Object.keys(palette ? palette.types : {})]);
      let i = 1;
      while (taken.has(`Subsystem${i}`)) i++;
      const defName = await prompt({
        title: "Make subsystem",
        label: `A new definition from ${chosen.length} block${chosen.length > 1 ? "s" : ""}: its name (a type name)`,
        value: `Subsystem${i}`,
        testid: "subsystem-name",
      });
      if (defName === null) return;
      if (!IDENT.test(defName) || taken.has(defName)) {
        toast(`${JSON.stringify(defName)}: a definition needs a new identifier for a name, not a kinetwork type nor another definition`);
        return;
      }
      const inst = freshName(defName.charAt(0).toLowerCase() + defName.slice(1), takenNames(body));
      const positions = Object.fromEntries((body.components || []).map((c) => [c.name, posOf(c.name) || { x: 0, y: 0 }]));
      const { body: next, definition } = makeSubsystem(body, chosen, defName, inst, positions);
      const { scopes, file, defCache } = studio();
      studio().update((d) => {
        const out = editInScope(d, scopes, { palette, docPath: file.path, defCache }, () => next);
        return orderKeys({ ...out, version: 2, definitions: { ...(out.definitions || {}), [defName]: definition } });
      });
      select([inst]);
      toast(`${defName}: a new definition with ${Object.keys(definition.ports).length} ports; double-click ${inst} to open it`, "info");
    },
    [body, posOf, select, toast],
  );

  const fold = useCallback(
    /** Folds the longest repeated pattern of the scope into instances of a new definition. */
    async () => {
      const found = findRepeat(body);
      if (!found) {
        toast("no pattern of blocks repeats here (three or more alike units, wired alike, one after the other)");
        return;
      }
      const { palette, hist } = studio();
      const taken = new Set([...Object.keys(hist.present.definitions || {}), ...Object.keys(palette ? palette.types : {})]);
      const joint = found.units[0].some((c) => /Revolute|Prismatic|Spherical|Universal|Cylindrical|Planar|FreeMotion/.test(c.type));
      const stem = joint ? "Link" : "Unit";
      let defName = stem;
      for (let i = 2; taken.has(defName); i++) defName = `${stem}${i}`;
      const kinds = found.units[0].map((c) => String(c.type).split(".").pop()).join(", ");
      defName = await prompt({
        title: "Fold into subsystems",
        label: `${found.n} alike units of ${found.p} blocks (${kinds}) become ${found.n} instances of a new definition: its name`,
        value: defName,
        testid: "fold-name",
      });
      if (defName === null) return;
      if (!IDENT.test(defName) || taken.has(defName)) {
        toast(`${JSON.stringify(defName)}: a definition needs a new identifier for a name, not a kinetwork type nor another definition`);
        return;
      }
      const { body: next, definition, instances } = foldRepeat(body, found, defName);
      const { scopes, file, defCache } = studio();
      // the blocks the studio placed itself are placed again, with the instances
      useStudio.setState((s) => ({ autoPos: { ...s.autoPos, [scopeKey]: {} } }));
      studio().update((d) => {
        const out = editInScope(d, scopes, { palette, docPath: file.path, defCache }, () => next);
        return orderKeys({ ...out, version: 2, definitions: { ...(out.definitions || {}), [defName]: definition } });
      });
      select([]);
      studio().fit();
      toast(`${found.n} units folded into ${defName} (${instances[0]} … ${instances[instances.length - 1]}); double-click one to open it, Undo to unfold`, "info");
    },
    [body, scopeKey, select, toast],
  );

  return useMemo(
    () => ({
      domainOf,
      checkConnection,
      connect,
      moved,
      nudge,
      remove,
      removeSelected,
      place,
      placeAtCentre,
      open,
      rename,
      askRename,
      setParam: setParamOf,
      setModelParam,
      renameModelParam,
      setSim,
      setField,
      setPort,
      copy,
      paste,
      duplicate,
      rotate,
      flip,
      selectAll,
      makeSub,
      fold,
    }),
    [domainOf, checkConnection, connect, moved, nudge, remove, removeSelected, place, placeAtCentre, open, rename, askRename, setParamOf, setModelParam, renameModelParam, setSim, setField, setPort, copy, paste, duplicate, rotate, flip, selectAll, makeSub, fold],
  );
}

/** The wire an edge id names: "a~b~i" -> {a, b}; "@port" -> {exposed}. */
export function edgeData(id) {
  if (id.startsWith("@")) return { exposed: id.slice(1) };
  const [a, b] = id.split("~");
  return a && b ? { a, b } : null;
}
