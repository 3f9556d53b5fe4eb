// The studio's state, in one zustand store (xyflow keeps its own the same way): what the
// server told us, the document with its undo history, the file it came from, where the
// diagram looks, what is selected, validation, runs, and the page's toasts and dialogs.
// Components read it through selectors; hooks/ hold the work that talks to the server.
import { create } from "zustand";
import { initHistory, pushEdit, redo, replacePresent, undo } from "./history.js";
import { editInScope, emptyModel } from "./model.js";

/**
 * @typedef {any} FileState
 * @property {string | null} path     root-relative path of the file, null before a first save
 * @property {string | null} text     the file's text as opened or last saved
 * @property {string | null} version  the server's version of that text (sent back with a save)
 * @property {string} baseline        JSON of the document as opened or saved: dirty when different
 * @property {string | null} example  the example's name, when opened from one
 */

/** @returns {FileState} */
export function newFile(doc = emptyModel()) {
  return { path: null, text: null, version: null, baseline: JSON.stringify(doc), example: null };
}

const NO_VALIDATION = { ok: null, problems: [], summary: null, doc: null };

let toastId = 0;

/**
 * @typedef {any} RunState
 * @property {string} [id]
 * @property {"starting" | "running" | "cancelling" | "done" | "failed" | "cancelled"} state
 * @property {number} progress
 * @property {string} [phase]     what a running run is doing: "compiling", "integrating", ...
 * @property {string} [kind]      "run" or "sweep"
 * @property {string | null} [error]
 * @property {any[]} [problems]
 */

export const useStudio = create((set, get) => ({
  /** @type {{libraries: any[], types: Record<string, any>} | null} */
  palette: null,
  /** GET /api/facts: methods, settings' defaults, the studio's limits */
  facts: null,
  hist: initHistory(emptyModel()),
  file: newFile(),
  /** the definitions opened, from the model inwards */
  scopes: /** @type {string[]} */ ([]),
  /** definitions read from files: root-relative path -> {status, model} */
  defCache: {},
  /** positions computed for blocks the layout does not place: scope key -> name -> {x, y} */
  autoPos: {},
  selection: /** @type {string[]} */ ([]),
  selectedEdges: /** @type {string[]} */ ([]),
  fitRequest: 0,
  /** the minimap asked for (true), put away (false), or shown where it covers no block (null) */
  minimap: /** @type {boolean | null} */ (null),
  /** the minimap would show by itself: room for it, its corner free of blocks when fitted */
  mapClear: true,
  validation: NO_VALIDATION,
  /** @type {RunState | null} */
  run: null,
  /** runs with results, latest first: {n, id, state, results, label, kind, members?} */
  runs: [],
  /** runs of the model now open (the counter restarts with another model) */
  runCount: 0,
  /** the 3-D views of runs whose results came ahead of them, by run id: {animation, note} */
  views: {},
  /** @type {{id: number, message: string, kind: string}[]} */
  toasts: [],
  dialog: null,
  /** unsaved work kept from an earlier session, offered back: {path, message, recover, discard} */
  offer: null,
  busy: null,
  /** the pointer's last place over the diagram (layout units), for paste */
  pointer: null,
  /** the 3-D view and the plots' time (s) */
  time: null,
  /** the right-click menu: {x, y, target} */
  menu: null,
  /** the side panel shown: "params", "json" or "analysis" */
  panel: "params",

  // -- the document ----------------------------------------------------------------------------
  isDirty: () => JSON.stringify(get().hist.present) !== get().file.baseline,
  /** An edit of the whole document: ``fn(doc)`` is the next one (one undo step). */
  update: (fn, merge = null) => set((s) => ({ hist: pushEdit(s.hist, fn(s.hist.present), merge) })),
  /** An edit of the scope shown (the model, or the definition opened). */
  editScope: (fn, merge = null) => {
    const { scopes, palette, file, defCache } = get();
    get().update((d) => editInScope(d, scopes, { palette, docPath: file.path, defCache }, fn), merge);
  },
  undo: () => set((s) => ({ hist: undo(s.hist) })),
  redo: () => set((s) => ({ hist: redo(s.hist) })),
  /** A document opened (from a file, an example, a recovery): no history, nothing selected. */
  load: (doc, file) =>
    set({
      hist: initHistory(doc),
      file,
      scopes: [],
      selection: [],
      selectedEdges: [],
      autoPos: {},
      validation: NO_VALIDATION,
      run: null,
      runs: [],
      runCount: 0,
      views: {},
      time: null,
      menu: null,
      fitRequest: get().fitRequest + 1,
    }),
  /** The document as the server wrote it, saved: the same model, no undo step. */
  saved: (doc, file) => set((s) => ({ hist: replacePresent(s.hist, doc), file })),

  // -- where the diagram looks, what is selected -----------------------------------------------
  setScopes: (scopes) => set({ scopes, selection: [], selectedEdges: [], menu: null, fitRequest: get().fitRequest + 1 }),
  select: (names, edges = []) => set({ selection: names, selectedEdges: edges }),
  setAutoPos: (key, pos) => set((s) => ({ autoPos: { ...s.autoPos, [key]: { ...(s.autoPos[key] || {}), ...pos } } })),
  fit: () => set((s) => ({ fitRequest: s.fitRequest + 1 })),
  setMinimap: (minimap) => set({ minimap }),
  setMapClear: (mapClear) => set({ mapClear }),
  setPointer: (pointer) => set({ pointer }),
  setMenu: (menu) => set({ menu }),
  setPanel: (panel) => set({ panel }),
  setTime: (time) => set({ time }),

  // -- messages ------------------------------------------------------------------------------
  toast: (message, kind = "error") => {
    const id = ++toastId;
    // the same message again replaces the one shown (a repeated refusal is one toast)
    set((s) => ({ toasts: [...s.toasts.filter((t) => t.message !== message).slice(-3), { id, message, kind }] }));
    setTimeout(() => get().dismiss(id), kind === "error" ? 8000 : 6000);
  },
  dismiss: (id) => set((s) => ({ toasts: s.toasts.filter((t) => t.id !== id) })),
  setDialog: (dialog) => set({ dialog }),
  setOffer: (offer) => set({ offer }),
  setBusy: (busy) => set({ busy }),
}));

/** The store's state now, outside React (event handlers, timers). */
export const studio = () => useStudio.getState();

/** Where the plots' cursor was put since the latest run's results were drawn (null: nowhere
 * yet): a 3-D view that comes after its plots starts there, as it would have followed it. */
export const cursorSinceRun = { t: /** @type {number | null} */ (null) };
