// The studio: palette | diagram | parameters, with the probe plots and the 3-D view below.
// The document is a model file's top-level object; every edit makes a new one (undo/redo
// keep them), validation follows edits (debounced), Run posts it to the server.
import { useCallback, useEffect, useMemo, useReducer, useRef, useState } from "react";
import { MarkerType, useReactFlow } from "@xyflow/react";
import { api, OPEN, EXAMPLE } from "./api.js";
import Canvas from "./Canvas.jsx";
import Palette from "./Palette.jsx";
import ParamPanel from "./ParamPanel.jsx";
import Plots, { makeBus, OVERLAY } from "./Plots.jsx";
import Viewer from "./Viewer.jsx";
import Problems from "./Problems.jsx";
import { OpenDialog, PromptDialog } from "./Dialogs.jsx";
import {
  DOMAIN_COLORS,
  IDENT,
  SCALE,
  addComponent,
  autoLayout,
  clone,
  connectProblem,
  emptyModel,
  freshName,
  nameStem,
  orderKeys,
  portDomain,
  portSide,
  removeComponents,
  renameComponent,
  resolveDef,
  resolveScope,
  setParam,
  takenNames,
  typeInfo,
  updateDefinition,
  definitionSource,
  shapeProblem,
} from "./model.js";
import { makeSubsystem } from "./subsystem.js";

const K = (window.__kinetwork = window.__kinetwork || {});
K.timings = K.timings || {};
K.errors = K.errors || [];

// -- undo history ----------------------------------------------------------------------------
function historyReducer(h, a) {
  switch (a.type) {
    case "update": {
      const next = a.fn(h.present);
      // an edit that changes nothing is no step to undo
      if (!next || next === h.present || JSON.stringify(next) === JSON.stringify(h.present)) return h;
      return { past: [...h.past.slice(-199), h.present], present: next, future: [] };
    }
    case "undo":
      if (!h.past.length) return h;
      return { past: h.past.slice(0, -1), present: h.past[h.past.length - 1], future: [h.present, ...h.future] };
    case "redo":
      if (!h.future.length) return h;
      return { past: [...h.past, h.present], present: h.future[0], future: h.future.slice(1) };
    case "replace":
      return { ...h, present: a.doc };
    case "reset":
      return { past: [], present: a.doc, future: [] };
    default:
      return h;
  }
}

// -- problems: on the scope and component they name ------------------------------------------
function placeOf(problem) {
  const msg = String(problem.message || "").replace(/^[^\s:]+\.json: /, "");
  const def = /^definitions\.([A-Za-z_][A-Za-z0-9_]*)\.(.*)$/s.exec(msg);
  const rest = def ? def[2] : msg;
  let comp = def ? null : problem.component || null;
  let param = def ? null : problem.param || null;
  let conn = def ? null : problem.connection;
  const cm = /^components\[\d+\] "([^"]+)"(?: params\.([A-Za-z_][A-Za-z0-9_]*))?/.exec(rest);
  if (cm) {
    comp = comp || cm[1];
    param = param || cm[2] || null;
  }
  const nm = /^connections\[(\d+)\]/.exec(rest);
  if (nm && (conn === null || conn === undefined)) conn = Number(nm[1]);
  return { scope: def ? def[1] : "", component: comp, param, connection: conn ?? null, message: problem.message };
}

function sameList(a, b) {
  return a.length === b.length && a.every((x, i) => x === b[i]);
}

let toastId = 0;

export default function App() {
  const flow = useReactFlow();
  const [palette, setPalette] = useState(null);
  const [hist, dispatch] = useReducer(historyReducer, null, () => ({ past: [], present: emptyModel(), future: [] }));
  const doc = hist.present;
  const [file, setFile] = useState(() => ({ path: null, text: null, baseline: JSON.stringify(emptyModel()), example: null }));
  const [scopes, setScopes] = useState([]);
  const [defCache, setDefCache] = useState({});
  const [autoPos, setAutoPos] = useState({});
  const [selection, setSelection] = useState([]);
  const [selectRequest, setSelectRequest] = useState(null);
  const [fitRequest, setFitRequest] = useState(0);
  const [validation, setValidation] = useState({ ok: null, problems: [], summary: null });
  const [runState, setRunState] = useState(null);
  const [runs, setRuns] = useState([]);
  const [toasts, setToasts] = useState([]);
  const [dialog, setDialog] = useState(null);
  const [busy, setBusy] = useState(null);
  const clipboard = useRef(null);
  const selectedEdges = useRef([]);
  const runCounter = useRef(0);
  const polling = useRef(null);
  const viewerRef = useRef(null);
  const bus = useMemo(() => makeBus(), []);
  bus.cursor = (t) => {
    K.cursorTime = t;
    if (viewerRef.current) viewerRef.current.setTime(t);
  };

  const toast = useCallback((message, kind = "error") => {
    const id = ++toastId;
    // the same message again replaces the one shown (a repeated refusal is one toast)
    setToasts((ts) => [...ts.filter((t) => t.message !== message).slice(-3), { id, message, kind }]);
    setTimeout(() => setToasts((ts) => ts.filter((t) => t.id !== id)), kind === "error" ? 8000 : 4000);
  }, []);

  // -- the palette, then the file named in the URL ----------------------------------------
  useEffect(() => {
    let gone = false;
    api
      .palette()
      .then((p) => {
        if (gone) return;
        const types = {};
        for (const lib of p.libraries) for (const t of lib.types) types[t.type] = t;
        setPalette({ libraries: p.libraries, types });
        K.timings.paletteReady = performance.now();
        if (OPEN) openModel({ path: OPEN });
        else if (EXAMPLE) openModel({ example: EXAMPLE });
      })
      .catch((e) => toast(`The palette could not be loaded: ${e.message}`));
    return () => {
      gone = true;
    };
    // eslint-disable-next-line react-hooks/exhaustive-deps
  }, []);

  const rootCtx = useMemo(() => ({ palette, doc, docPath: file.path, defCache }), [palette, doc, file.path, defCache]);
  const scope = scopes.length ? scopes[scopes.length - 1] : null;
  const resolved = useMemo(() => resolveScope(scopes, rootCtx), [scopes, rootCtx]);
  const body = resolved ? resolved.body : doc;
  const ctx = resolved ? resolved.ctx : rootCtx;
  const scopeKey = scopes.join("/");

  // a scope whose definition is gone (undo, delete): back to the model
  useEffect(() => {
    if (scopes.length && !resolved) {
      const pending = scopes.some((s) => {
        const r = resolveDef(s, rootCtx);
        return r && !r.body && !r.missing;
      });
      if (!pending) setScopes([]);
    }
  }, [scopes, resolved, rootCtx]);

  // -- definitions read from files: fetch what the model's subsystems need ------------------
  useEffect(() => {
    if (!palette) return;
    const want = new Set();
    const seen = new Set();
    const visit = (b, c, depth) => {
      if (depth > 16) return;
      for (const comp of b.components || []) {
        if (palette.types[comp.type] || seen.has(`${c.docPath}|${comp.type}`)) continue;
        seen.add(`${c.docPath}|${comp.type}`);
        const r = resolveDef(comp.type, c);
        if (!r) continue;
        if (r.body) visit(r.body, r.ctx, depth + 1);
        else if (r.src.kind === "file" && !defCache[r.src.key]) want.add(r.src.key);
      }
      for (const [name, entry] of Object.entries(b.definitions || {})) {
        if (entry && typeof entry === "object" && !entry.file) visit(entry, c, depth + 1);
        else if (entry && typeof entry.file === "string") {
          const r = resolveDef(name, c);
          if (r && !r.body && r.src.kind === "file" && !defCache[r.src.key]) want.add(r.src.key);
        }
      }
    };
    visit(doc, rootCtx, 0);
    if (!want.size) return;
    setDefCache((dc) => {
      const next = { ...dc };
      for (const key of want) next[key] = { status: "loading" };
      return next;
    });
    for (const key of want) {
      api
        .openPath(key)
        .then((r) => setDefCache((dc) => ({ ...dc, [key]: shapeProblem(r.model) ? { status: "missing" } : { status: "ok", model: r.model } })))
        .catch(() => setDefCache((dc) => ({ ...dc, [key]: { status: "missing" } })));
    }
  }, [doc, defCache, palette, rootCtx]);

  // -- positions: the layout's, else computed -----------------------------------------------
  const posOf = useCallback(
    (name) => {
      const l = body.layout && body.layout[name];
      if (l && typeof l.x === "number" && typeof l.y === "number") return l;
      const a = autoPos[scopeKey] && autoPos[scopeKey][name];
      return a || null;
    },
    [body, autoPos, scopeKey],
  );

  useEffect(() => {
    const missing = (body.components || []).map((c) => c.name).filter((n) => !posOf(n));
    if (!missing.length) return;
    setAutoPos((ap) => ({ ...ap, [scopeKey]: { ...(ap[scopeKey] || {}), ...autoLayout(body, missing) } }));
  }, [body, posOf, scopeKey]);

  // a definition opened without a layout: the server lays it out (as it does a model)
  const laidOut = useRef(new Set());
  useEffect(() => {
    if (!scopes.length || !resolved) return;
    const layout = body.layout || {};
    const comps = body.components || [];
    if (!comps.length || comps.some((c) => layout[c.name]) || laidOut.current.has(scopeKey)) return;
    laidOut.current.add(scopeKey);
    const model = { format: "kinetwork.model", version: 2, name: scope };
    for (const k of ["parameters", "ports", "components", "connections"]) if (body[k] !== undefined) model[k] = body[k];
    if (body.definitions) model.definitions = body.definitions;
    api
      .layout(model, resolved.ctx.docPath)
      .then((lr) => {
        const got = (lr && lr.layout) || {};
        const pos = {};
        for (const c of comps) {
          const p = got[c.name];
          if (p && typeof p.x === "number" && typeof p.y === "number") pos[c.name] = { x: p.x, y: p.y };
        }
        if (Object.keys(pos).length) {
          setAutoPos((ap) => ({ ...ap, [scopeKey]: { ...(ap[scopeKey] || {}), ...pos } }));
          setFitRequest((n) => n + 1);
        }
      })
      .catch(() => {
        /* the studio's own layout stays */
      });
  }, [scopes.length, resolved, body, scope, scopeKey]);

  // -- validation, debounced ---------------------------------------------------------------
  const validateSeq = useRef(0);
  useEffect(() => {
    if (!palette) return undefined;
    const seq = ++validateSeq.current;
    const id = setTimeout(() => {
      api
        .validate(doc, file.path)
        .then((r) => seq === validateSeq.current && setValidation({ ok: r.ok, problems: r.problems || [], summary: r.summary || null, doc }))
        .catch((e) => {
          if (seq !== validateSeq.current) return;
          const problems = e.problems && e.problems.length ? e.problems : [{ message: e.message, component: null, param: null, connection: null }];
          setValidation({ ok: false, problems, summary: null, doc });
        });
    }, 350);
    return () => clearTimeout(id);
  }, [doc, palette, file.path]);

  const runProblems = useMemo(() => (runState && runState.problems) || [], [runState]);
  const places = useMemo(
    () => [...validation.problems.map(placeOf), ...runProblems.map((p) => ({ ...placeOf(p), run: true }))],
    [validation.problems, runProblems],
  );
  const here = useMemo(() => places.filter((p) => p.scope === (scope || "")), [places, scope]);
  const problemsOf = useCallback((name) => here.filter((p) => p.component === name), [here]);

  // -- what the diagram shows ----------------------------------------------------------------
  const nodesIn = useMemo(() => {
    const conns = body.connections || [];
    return (body.components || []).map((c) => {
      const info = typeInfo(c.type, ctx);
      const p = posOf(c.name) || { x: 0, y: 0 };
      let ports = null;
      if (!info) {
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
          problems: problemsOf(c.name),
          subsystem: !!(info && info.subsystem),
          unknown: !info && !(r && !r.body && !r.missing),
        },
      };
    });
  }, [body, ctx, posOf, problemsOf]);

  // inside a definition: its exposed ports, each beside the inner port it stands for
  const exposed = useMemo(() => {
    if (!scopes.length) return [];
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
      const moved = autoPos[scopeKey] && autoPos[scopeKey][`@${pname}`];
      return { pname, ref, cname, port, domain, side, pos: moved || { x: at.x + shift[0], y: at.y + shift[1] } };
    });
  }, [scopes.length, body, ctx, posOf, autoPos, scopeKey]);

  const nodesShown = useMemo(
    () => [
      ...nodesIn,
      ...exposed.map((e) => ({
        id: `@${e.pname}`,
        type: "extport",
        position: { x: e.pos.x * SCALE, y: e.pos.y * SCALE },
        data: { name: e.pname, domain: e.domain, side: e.side, ref: e.ref },
      })),
    ],
    [nodesIn, exposed],
  );

  const edgesIn = useMemo(() => {
    const badConn = new Set(here.filter((p) => p.connection !== null && p.connection !== undefined).map((p) => p.connection));
    return (body.connections || []).map(([a, b], i) => {
      const [ca, pa] = String(a).split(".");
      const [cb, pb] = String(b).split(".");
      let dom = portDomain(body, a, ctx);
      if (!dom || dom === "any") dom = portDomain(body, b, ctx) || dom || "any";
      const bad = badConn.has(i);
      const color = bad ? "#e03131" : DOMAIN_COLORS[dom] || "#888";
      // a signal wire points at its input
      const arrow = { type: MarkerType.ArrowClosed, color, width: 14, height: 14 };
      const markers = dom === "signal_in" || dom === "signal_out"
        ? portDomain(body, b, ctx) === "signal_in" ? { markerEnd: arrow } : portDomain(body, a, ctx) === "signal_in" ? { markerStart: arrow } : {}
        : {};
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
  }, [body, ctx, here]);

  const edgesShown = useMemo(
    () => [
      ...edgesIn,
      ...exposed.map((e) => ({
        id: `@${e.pname}`,
        source: `@${e.pname}`,
        sourceHandle: "port",
        target: e.cname,
        targetHandle: e.port,
        data: { exposed: e.pname },
        className: "kn-edge kn-edge-exposed",
        style: { stroke: DOMAIN_COLORS[e.domain] || "#888", strokeWidth: 1.6, strokeDasharray: "6 4" },
      })),
    ],
    [edgesIn, exposed],
  );

  // -- editing -------------------------------------------------------------------------------
  const editScope = useCallback(
    (fn) => {
      dispatch({
        type: "update",
        fn: (d) => {
          if (!scopes.length) return fn(d);
          // every definition on the way is made inline, so the edit is the one used
          let c = { palette, doc: d, docPath: file.path, defCache };
          let out = d;
          for (let i = 0; i < scopes.length; i++) {
            const r = resolveDef(scopes[i], c);
            if (!r || !r.body) return d;
            const last = i === scopes.length - 1;
            if (last) out = updateDefinition(out, file.path, scopes[i], r, fn);
            else if (r.src.kind === "file") out = updateDefinition(out, file.path, scopes[i], r, (x) => x);
            c = r.ctx;
          }
          return out;
        },
      });
    },
    [scopes, palette, file.path, defCache],
  );

  const domainOf = useCallback(
    (path) => {
      if (path.startsWith("@")) {
        const e = exposed.find((x) => `@${x.pname}.port` === path);
        return e ? "any" : null;       // an exposed port takes the domain of what it is given
      }
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
      return connectProblem({ path: a, domain: da }, { path: b, domain: db }, body.connections);
    },
    [body, domainOf],
  );

  const onConnectPorts = useCallback(
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

  const onMoved = useCallback(
    (moved) => {
      const ports = Object.fromEntries(Object.entries(moved).filter(([k]) => k.startsWith("@")));
      if (Object.keys(ports).length) setAutoPos((ap) => ({ ...ap, [scopeKey]: { ...(ap[scopeKey] || {}), ...ports } }));
      moved = Object.fromEntries(Object.entries(moved).filter(([k]) => !k.startsWith("@")));
      if (!Object.keys(moved).length) return;
      editScope((s) => {
        const old = s.layout || {};
        const same = Object.entries(moved).every(([k, v]) => old[k] && old[k].x === v.x && old[k].y === v.y);
        return same ? s : { ...s, layout: { ...old, ...moved } };
      });
    },
    [editScope, scopeKey],
  );

  const onDelete = useCallback(
    (names, edges) => {
      const unexpose = new Set([
        ...names.filter((n) => n.startsWith("@")).map((n) => n.slice(1)),
        ...edges.filter((e) => e && e.exposed).map((e) => e.exposed),
      ]);
      const gone = new Set(names.filter((n) => !n.startsWith("@")));
      const drop = new Set(edges.filter((e) => e && !e.exposed).map((e) => `${e.a}\u0000${e.b}`));
      editScope((s) => {
        let next = gone.size ? removeComponents(s, [...gone]) : s;
        if (unexpose.size) next = { ...next, ports: Object.fromEntries(Object.entries(next.ports || {}).filter(([k]) => !unexpose.has(k))) };
        if (drop.size) next = { ...next, connections: (next.connections || []).filter(([a, b]) => !drop.has(`${a}\u0000${b}`)) };
        return next;
      });
      setSelection([]);
    },
    [editScope],
  );

  const placeType = useCallback(
    (type, flowPos) => {
      const name = freshName(nameStem(type), takenNames(body));
      const pos = { x: Math.round(flowPos.x / SCALE / 10) * 10, y: Math.round(flowPos.y / SCALE / 10) * 10 };
      editScope((s) => addComponent(s, { name, type, params: {} }, pos));
      setSelectRequest({ names: [name] });
      setSelection([name]);
    },
    [body, editScope],
  );

  const addAtCentre = useCallback(
    (type) => {
      const el = document.querySelector(".kn-canvas");
      const r = el ? el.getBoundingClientRect() : { left: 0, top: 0, width: 400, height: 300 };
      const p = flow.screenToFlowPosition({ x: r.left + r.width / 2, y: r.top + r.height / 2 });
      placeType(type, { x: p.x - 58 + (Math.random() - 0.5) * 60, y: p.y - 32 + (Math.random() - 0.5) * 60 });
    },
    [flow, placeType],
  );

  const onSelection = useCallback((names, edges) => {
    setSelection((old) => (sameList(old, names) ? old : names));
    selectedEdges.current = edges || [];
  }, []);

  // Delete / Backspace: the selected blocks (with their wires) and the selected wires
  const deleteSelected = useCallback(() => {
    const edges = selectedEdges.current.filter(Boolean);
    if (!selection.length && !edges.length) return;
    onDelete(selection, edges);
    selectedEdges.current = [];
  }, [selection, onDelete]);

  const onOpenNode = useCallback(
    (name) => {
      const comp = (body.components || []).find((c) => c.name === name);
      if (!comp) return;
      const r = resolveDef(comp.type, ctx);
      if (!r) return;
      if (!r.body) {
        toast(`the definition of ${comp.type} is ${r.missing ? "not found" : "still loading"}`);
        return;
      }
      setScopes((s) => [...s, comp.type]);
      setSelection([]);
      setSelectRequest({ names: [] });
      setFitRequest((n) => n + 1);
    },
    [body, ctx, toast],
  );

  const onRename = useCallback(
    (from, to) => {
      if (to === from) return;
      if (!IDENT.test(to)) {
        toast(`${JSON.stringify(to)} is not a component name: letters, digits and underscores, not starting with a digit`);
        return;
      }
      if (takenNames(body).has(to)) {
        toast(`there is already a component named ${to}`);
        return;
      }
      editScope((s) => renameComponent(s, from, to));
      setSelectRequest({ names: [to] });
      setSelection([to]);
    },
    [body, editScope, toast],
  );

  const onSetParam = useCallback((cname, key, value) => editScope((s) => setParam(s, cname, key, value)), [editScope]);

  const onModelParam = useCallback(
    (name, value) =>
      editScope((s) => {
        const params = { ...(s.parameters || {}) };
        if (value === undefined) delete params[name];
        else params[name] = value;
        return orderKeys({ ...s, parameters: params });
      }),
    [editScope],
  );
  const onRenameModelParam = useCallback(
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
  const onSim = useCallback(
    (key, value) =>
      dispatch({
        type: "update",
        fn: (d) => {
          const sim = { ...(d.simulation || {}) };
          if (value === undefined) delete sim[key];
          else sim[key] = value;
          return orderKeys({ ...d, simulation: sim });
        },
      }),
    [],
  );
  const onField = useCallback(
    (key, value) => {
      if (key === "name" && !scopes.length) dispatch({ type: "update", fn: (d) => ({ ...d, name: value }) });
      else editScope((s) => orderKeys({ ...s, [key]: value }));
    },
    [editScope, scopes.length],
  );
  const onPort = useCallback(
    (name, ref) =>
      editScope((s) => {
        const ports = { ...(s.ports || {}) };
        if (ref === undefined) delete ports[name];
        else ports[name] = ref;
        return { ...s, ports };
      }),
    [editScope],
  );

  // -- copy, paste, make subsystem --------------------------------------------------------
  const copy = useCallback(() => {
    const names = new Set(selection);
    if (!names.size) return;
    const comps = (body.components || []).filter((c) => names.has(c.name));
    clipboard.current = {
      components: clone(comps),
      connections: (body.connections || []).filter(([a, b]) => names.has(a.split(".")[0]) && names.has(b.split(".")[0])),
      positions: Object.fromEntries(comps.map((c) => [c.name, posOf(c.name) || { x: 0, y: 0 }])),
    };
    toast(`copied ${comps.length} component${comps.length > 1 ? "s" : ""}`, "info");
  }, [selection, body, posOf, toast]);

  const paste = useCallback(() => {
    const cb = clipboard.current;
    if (!cb) return;
    const taken = takenNames(body);
    const rename = {};
    for (const c of cb.components) {
      const n = freshName(c.name, taken);
      taken.add(n);
      rename[c.name] = n;
    }
    const re = (ref) => {
      const [c, p] = ref.split(".");
      return `${rename[c]}.${p}`;
    };
    editScope((s) => {
      let next = s;
      for (const c of cb.components) {
        const p = cb.positions[c.name];
        next = addComponent(next, { ...clone(c), name: rename[c.name] }, { x: p.x + 30, y: p.y + 30 });
      }
      return { ...next, connections: [...(next.connections || []), ...cb.connections.map(([a, b]) => [re(a), re(b)])] };
    });
    const names = Object.values(rename);
    setSelectRequest({ names });
    setSelection(names);
  }, [body, editScope]);

  const makeSub = useCallback(() => {
    if (!selection.length) {
      toast("select the blocks to make a subsystem of (drag a box around them, or Ctrl+click)");
      return;
    }
    const taken = new Set([...Object.keys(doc.definitions || {}), ...Object.keys(palette ? palette.types : {})]);
    let i = 1;
    while (taken.has(`Subsystem${i}`)) i++;
    setDialog({
      kind: "prompt",
      title: "Make subsystem",
      label: `A new definition from ${selection.length} block${selection.length > 1 ? "s" : ""}: its name (a type name)`,
      value: `Subsystem${i}`,
      testid: "subsystem-name",
      onOk: (defName) => {
        if (!IDENT.test(defName) || taken.has(defName)) {
          toast(`${JSON.stringify(defName)}: a definition needs a new identifier for a name, not a kinetwork type nor another definition`);
          return;
        }
        const inst = freshName(defName.charAt(0).toLowerCase() + defName.slice(1), takenNames(body));
        const positions = Object.fromEntries((body.components || []).map((c) => [c.name, posOf(c.name) || { x: 0, y: 0 }]));
        const { body: next, definition } = makeSubsystem(body, selection, defName, inst, positions);
        const scopesNow = scopes;
        dispatch({
          type: "update",
          fn: (d) => {
            let out;
            if (!scopesNow.length) out = { ...d, ...next };
            else {
              let c = { palette, doc: d, docPath: file.path, defCache };
              out = d;
              for (let k = 0; k < scopesNow.length; k++) {
                const r = resolveDef(scopesNow[k], c);
                if (!r || !r.body) return d;
                out = updateDefinition(out, file.path, scopesNow[k], r, k === scopesNow.length - 1 ? () => next : (x) => x);
                c = r.ctx;
              }
            }
            return orderKeys({ ...out, version: 2, definitions: { ...(out.definitions || {}), [defName]: definition } });
          },
        });
        setSelectRequest({ names: [inst] });
        setSelection([inst]);
        toast(`${defName}: a new definition with ${Object.keys(definition.ports).length} ports; double-click ${inst} to open it`, "info");
      },
    });
  }, [selection, doc, palette, body, posOf, scopes, file.path, defCache, toast]);

  // -- files ---------------------------------------------------------------------------------
  const openModel = useCallback(
    async (src) => {
      setBusy("Opening…");
      try {
        const r = src.path ? await api.openPath(src.path) : await api.openExample(src.example);
        const model = r.model;
        const bad = shapeProblem(model);
        if (bad) {
          toast(`cannot show ${src.path || src.example} as a diagram: ${bad}`);
          return;
        }
        dispatch({ type: "reset", doc: model });
        setFile({ path: r.path || null, text: r.text, baseline: JSON.stringify(model), example: src.example || null });
        setScopes([]);
        setSelection([]);
        setSelectRequest({ names: [] });
        setAutoPos({});
        laidOut.current = new Set();
        setRuns([]);
        setRunState(null);
        setValidation({ ok: null, problems: [], summary: null });
        setDialog(null);
        const url = new URL(window.location.href);
        if (r.path) url.searchParams.set("open", r.path);
        else url.searchParams.delete("open");
        window.history.replaceState(null, "", url);
        const layout = model.layout || {};
        const comps = model.components || [];
        if (comps.length && !comps.some((c) => layout[c.name])) {
          try {
            const lr = await api.layout(model, r.path);
            const got = (lr && (lr.layout || lr)) || {};
            const pos = {};
            for (const c of comps) {
              const p = got[c.name];
              if (p && typeof p.x === "number" && typeof p.y === "number") pos[c.name] = { x: p.x, y: p.y };
            }
            if (Object.keys(pos).length) setAutoPos((ap) => ({ ...ap, "": { ...(ap[""] || {}), ...pos } }));
          } catch {
            /* no layout service: the studio lays the blocks out itself */
          }
        }
        setFitRequest((n) => n + 1);
        K.timings.opened = performance.now();
      } catch (e) {
        toast(`cannot open ${src.path || src.example}: ${e.message}`);
      } finally {
        setBusy(null);
      }
    },
    [toast],
  );

  const newModel = useCallback(() => {
    dispatch({ type: "reset", doc: emptyModel() });
    setFile({ path: null, text: null, baseline: JSON.stringify(emptyModel()), example: null });
    setScopes([]);
    setAutoPos({});
    setRuns([]);
    setRunState(null);
    const url = new URL(window.location.href);
    url.searchParams.delete("open");
    window.history.replaceState(null, "", url);
  }, []);

  const dirty = JSON.stringify(doc) !== file.baseline;

  const withLayout = useCallback(
    (d) => {
      // what is shown is what is saved: computed positions join the layout
      const layout = { ...(d.layout || {}) };
      for (const c of d.components || []) {
        if (!layout[c.name]) {
          const p = autoPos[""] && autoPos[""][c.name];
          if (p) layout[c.name] = { x: Math.round(p.x), y: Math.round(p.y) };
        }
      }
      let out = { ...d, layout };
      if (d.definitions) {
        const defs = {};
        for (const [name, entry] of Object.entries(d.definitions)) {
          if (entry && !entry.file && Array.isArray(entry.components) && autoPos[name]) {
            const l = { ...(entry.layout || {}) };
            for (const c of entry.components) if (!l[c.name] && autoPos[name][c.name]) l[c.name] = autoPos[name][c.name];
            defs[name] = { ...entry, layout: l };
          } else defs[name] = entry;
        }
        out = { ...out, definitions: defs };
      }
      return orderKeys(out);
    },
    [autoPos],
  );

  const saveTo = useCallback(
    async (path) => {
      const unchanged = !dirty && path === file.path && file.text != null;
      const model = unchanged ? doc : withLayout(doc);
      setBusy("Saving…");
      try {
        const r = await api.save(path, model, unchanged ? file.text : null);
        let saved = model;
        try {
          saved = JSON.parse(r.text);
        } catch {
          /* keep what was sent */
        }
        if (!unchanged) dispatch({ type: "replace", doc: saved });
        setFile({ path, text: r.text, baseline: JSON.stringify(unchanged ? doc : saved), example: null });
        const url = new URL(window.location.href);
        url.searchParams.set("open", path);
        window.history.replaceState(null, "", url);
        toast(`saved ${path} (${r.bytes} bytes)`, "info");
        K.lastSave = { path, bytes: r.bytes, unchanged };
      } catch (e) {
        toast(`cannot save ${path}: ${e.message}`);
      } finally {
        setBusy(null);
      }
    },
    [dirty, file, doc, withLayout, toast],
  );

  const saveAs = useCallback(() => {
    setDialog({
      kind: "prompt",
      title: "Save as",
      label: "File (relative to the folder the studio was started in)",
      value: file.path || `${doc.name || "model"}.json`,
      testid: "save-path",
      onOk: (p) => {
        const path = p.trim();
        if (!path) return;
        saveTo(path.endsWith(".json") ? path : `${path}.json`);
      },
    });
  }, [file.path, doc.name, saveTo]);

  const save = useCallback(() => (file.path ? saveTo(file.path) : saveAs()), [file.path, saveTo, saveAs]);

  // -- running ---------------------------------------------------------------------------------
  const stopPolling = () => {
    if (polling.current) clearTimeout(polling.current);
    polling.current = null;
  };

  const run = useCallback(async () => {
    if (runState && (runState.state === "running" || runState.state === "starting")) return;
    const started = performance.now();
    K.timings.runClicked = started;
    setRunState({ state: "starting", progress: 0 });
    let id;
    try {
      id = (await api.run(doc, {}, file.path)).run;
    } catch (e) {
      setRunState({ state: "failed", progress: 0, error: e.message, problems: e.problems });
      toast(`cannot run: ${e.message}`);
      return;
    }
    setRunState({ id, state: "running", progress: 0 });
    const tick = async () => {
      let st;
      try {
        st = await api.runStatus(id);
      } catch (e) {
        setRunState({ id, state: "failed", progress: 0, error: e.message, problems: e.problems });
        toast(e.message);
        return;
      }
      if (st.state === "running") {
        setRunState({ id, state: "running", progress: st.progress || 0 });
        polling.current = setTimeout(tick, 120);
        return;
      }
      polling.current = null;
      setRunState({ id, state: st.state, progress: 1, error: st.error, problems: st.problems || [] });
      const res = st.results;
      if (res && res.t && res.t.length) {
        const n = ++runCounter.current;
        setRuns((rs) => [{ n, id, state: st.state, results: res }, ...rs].slice(0, OVERLAY + 1));
        K.lastRun = res;
        K.lastRunState = st.state;
        K.timings.runDone = performance.now();
        K.timings.runSeconds = (K.timings.runDone - started) / 1000;
      }
      if (st.state === "failed") toast(`the run failed: ${st.error || "no reason given"}`);
      else if (st.state === "cancelled") toast("run cancelled: the plots show what was computed", "info");
    };
    polling.current = setTimeout(tick, 60);
  }, [runState, doc, file.path, toast]);

  const cancel = useCallback(async () => {
    if (!runState || !runState.id || runState.state !== "running") return;
    try {
      await api.cancel(runState.id);
    } catch (e) {
      toast(e.message);
    }
  }, [runState, toast]);

  useEffect(() => () => stopPolling(), []);

  // plots drawn: the time from Run to results on screen
  useEffect(() => {
    if (!runs.length) return undefined;
    const id = requestAnimationFrame(() => {
      K.timings.plotted = performance.now();
      if (K.timings.runClicked) K.timings.runToPlot = (K.timings.plotted - K.timings.runClicked) / 1000;
    });
    return () => cancelAnimationFrame(id);
  }, [runs]);

  // -- keyboard -----------------------------------------------------------------------------------
  useEffect(() => {
    const onKey = (e) => {
      const t = e.target;
      if (t && (t.tagName === "INPUT" || t.tagName === "TEXTAREA" || t.tagName === "SELECT" || t.isContentEditable)) return;
      const mod = e.ctrlKey || e.metaKey;
      if (!mod && (e.key === "Delete" || e.key === "Backspace")) {
        e.preventDefault();
        deleteSelected();
        return;
      }
      if (!mod) return;
      const k = e.key.toLowerCase();
      if (k === "z" && !e.shiftKey) dispatch({ type: "undo" });
      else if (k === "y" || (k === "z" && e.shiftKey)) dispatch({ type: "redo" });
      else if (k === "c") copy();
      else if (k === "v") paste();
      else if (k === "s") save();
      else return;
      e.preventDefault();
    };
    window.addEventListener("keydown", onKey);
    return () => window.removeEventListener("keydown", onKey);
  }, [copy, paste, save, deleteSelected]);

  // leaving the page with unsaved changes asks first
  useEffect(() => {
    if (!dirty) return undefined;
    const onLeave = (e) => {
      e.preventDefault();
      e.returnValue = "";
    };
    window.addEventListener("beforeunload", onLeave);
    return () => window.removeEventListener("beforeunload", onLeave);
  }, [dirty]);

  // -- the testing hook -------------------------------------------------------------------------
  K.doc = doc;
  K.file = file;
  K.dirty = dirty;
  K.validation = validation;
  K.validated = validation.doc === doc;     // the answer is about the document shown
  K.runState = runState;
  K.runs = runs;
  K.scopes = scopes;
  K.selection = selection;
  K.setTime = (t) => {
    bus.setTime(t);
    if (viewerRef.current) viewerRef.current.setTime(t);
  };
  K.viewer = () => viewerRef.current;

  const definitionsList = useMemo(() => {
    if (!palette) return [];
    const names = new Set(Object.keys(doc.definitions || {}));
    for (const c of doc.components || []) if (!palette.types[c.type] && definitionSource(doc, file.path, c.type, palette)) names.add(c.type);
    return [...names].map((n) => typeInfo(n, rootCtx)).filter(Boolean);
  }, [doc, palette, rootCtx, file.path]);

  const onViewer = useCallback((v) => {
    viewerRef.current = v;
  }, []);

  const running = runState && (runState.state === "running" || runState.state === "starting");
  const latest = runs[0];
  const errorCount = places.length;

  return (
    <div className="kn-app">
      <header className="kn-bar">
        <div className="kn-brand" title="kinetwork studio">
          <svg viewBox="0 0 16 16" width="18" height="18">
            <circle cx="4" cy="4" r="3" fill="#5f5f5f" />
            <circle cx="12" cy="12" r="3" fill="#007f00" />
            <path d="M4 4L12 12" stroke="#404040" strokeWidth="2" />
          </svg>
          kinetwork
        </div>
        <div className="kn-group">
          <button className="kn-btn" data-testid="new" onClick={newModel} title="A new, empty model">New</button>
          <button className="kn-btn" data-testid="open" onClick={() => setDialog({ kind: "open" })} title="Open a model file or an example">Open…</button>
          <button className="kn-btn" data-testid="save" onClick={save} title="Save (Ctrl+S)">Save</button>
          <button className="kn-btn" data-testid="save-as" onClick={saveAs}>Save as…</button>
        </div>
        <div className="kn-group">
          <button className="kn-btn" data-testid="undo" disabled={!hist.past.length} onClick={() => dispatch({ type: "undo" })} title="Undo (Ctrl+Z)">↶</button>
          <button className="kn-btn" data-testid="redo" disabled={!hist.future.length} onClick={() => dispatch({ type: "redo" })} title="Redo (Ctrl+Y)">↷</button>
          <button className="kn-btn" data-testid="make-subsystem" disabled={!selection.length} onClick={makeSub} title="Turn the selected blocks into a subsystem">Make subsystem</button>
        </div>
        <div className="kn-group">
          <button className="kn-btn kn-run" data-testid="run" disabled={!!running} onClick={run} title="Simulate the model">▶ Run</button>
          <button className="kn-btn" data-testid="cancel" disabled={!running || !runState.id} onClick={cancel} title="Stop the run">■ Cancel</button>
          <div className={`kn-progress ${running ? "on" : ""}`} data-testid="progress" data-state={runState ? runState.state : "idle"}>
            <div className="kn-progress-bar" style={{ width: `${Math.round(((runState && runState.progress) || 0) * 100)}%` }} />
          </div>
          <span className="kn-status" data-testid="run-status">
            {runState
              ? runState.state === "running" || runState.state === "starting"
                ? `running ${Math.round((runState.progress || 0) * 100)} %`
                : runState.state === "done"
                  ? `done${K.timings.runSeconds ? ` in ${K.timings.runSeconds.toFixed(2)} s` : ""}`
                  : runState.state
              : ""}
          </span>
        </div>
        <div className="kn-file" data-testid="file" title={file.path || "not saved yet"}>
          {busy ? <span className="kn-muted">{busy} </span> : null}
          <b>{doc.name}</b>
          <span className="kn-muted"> · {file.path || (file.example ? `example ${file.example}` : "not saved")}</span>
          {dirty ? <span className="kn-dirty" data-testid="dirty" title="unsaved changes"> ●</span> : null}
        </div>
      </header>
      <div className="kn-main">
        <Palette palette={palette} definitions={definitionsList} onAdd={addAtCentre} />
        <div className="kn-center">
          <div className="kn-crumbs" data-testid="breadcrumb">
            <button className={`kn-crumb ${scopes.length ? "" : "here"}`} data-testid="crumb-0" onClick={() => setScopes([])}>
              {doc.name}
            </button>
            {scopes.map((s, i) => (
              <span key={i}>
                <span className="kn-crumb-sep">›</span>
                <button className={`kn-crumb ${i === scopes.length - 1 ? "here" : ""}`} data-testid={`crumb-${i + 1}`} onClick={() => setScopes(scopes.slice(0, i + 1))}>
                  {s}
                </button>
              </span>
            ))}
            <span className="kn-muted kn-small kn-hint">
              drag from the palette · wire port to port · box-select by dragging · wheel zooms, right-drag pans · Del · Ctrl+Z/Y · Ctrl+C/V · double-click a subsystem to open it
            </span>
          </div>
          <Canvas
            nodesIn={nodesShown}
            edgesIn={edgesShown}
            selectRequest={selectRequest}
            fitRequest={fitRequest}
            placed={(body.components || []).every((c) => posOf(c.name))}
            checkConnection={checkConnection}
            onConnectPorts={onConnectPorts}
            onRefused={toast}
            onMoved={onMoved}
            onDelete={onDelete}
            onDropType={placeType}
            onOpenNode={onOpenNode}
            onSelection={onSelection}
          />
          <div className="kn-results">
            <Plots runs={runs} bus={bus} running={running} progress={runState && runState.progress} status={runState && runState.state === "failed" ? `The run failed: ${runState.error}` : null} />
            <Viewer animation={latest ? latest.results.animation || null : null} bus={bus} onViewer={onViewer} />
          </div>
        </div>
        <div className="kn-right">
          <ParamPanel
            selected={selection}
            body={body}
            ctx={ctx}
            scope={scope}
            summary={validation.summary}
            infoOf={(type) => typeInfo(type, ctx)}
            problemsOf={problemsOf}
            scopeProblems={here}
            onRename={onRename}
            onSetParam={onSetParam}
            onOpenSubsystem={onOpenNode}
            onModelParam={onModelParam}
            onRenameModelParam={onRenameModelParam}
            onSim={onSim}
            onField={onField}
            onPort={onPort}
            onMakeSubsystem={makeSub}
          />
          <Problems
            places={places}
            ok={validation.ok}
            count={errorCount}
            onGo={(p) => {
              const target = p.scope ? [p.scope] : [];
              if (!sameList(target, scopes)) setScopes(target);
              if (p.component) {
                setSelectRequest({ names: [p.component] });
                setSelection([p.component]);
              }
            }}
          />
        </div>
      </div>
      <div className="kn-toasts">
        {toasts.map((t) => (
          <div key={t.id} className={`kn-toast ${t.kind}`} data-testid="toast" onClick={() => setToasts((ts) => ts.filter((x) => x.id !== t.id))}>
            {t.message}
          </div>
        ))}
      </div>
      {dialog && dialog.kind === "open" ? (
        <OpenDialog dirty={dirty} onOpen={openModel} onClose={() => setDialog(null)} />
      ) : null}
      {dialog && dialog.kind === "prompt" ? (
        <PromptDialog
          {...dialog}
          onClose={() => setDialog(null)}
          onOk={(v) => {
            setDialog(null);
            dialog.onOk(v);
          }}
        />
      ) : null}
    </div>
  );
}
