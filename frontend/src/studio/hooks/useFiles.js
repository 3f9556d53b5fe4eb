// Files: open, new, save and save as, never losing work. New and Open ask before unsaved
// changes are dropped, and so does closing the tab; a save carries the version of the file it
// was based on, so a file changed on disk since (another editor, another studio) is not
// overwritten without asking; the open model is autosaved to a recovery file beside it,
// offered again when it is next opened.
import { useCallback, useEffect } from "react";
import { api } from "../api.js";
import { emptyModel, orderKeys, shapeProblem } from "../model.js";
import { newFile, studio, useStudio } from "../store.js";
import { TESTING, trace } from "../testing.js";
import { forgetJobs } from "./useRun.js";

/** Seconds after the last edit before the model is autosaved. */
export const AUTOSAVE_MS = 1500;
/** This page's session: a recovery it wrote itself is not offered back to it. */
export const SESSION = `${Date.now().toString(36)}-${Math.random().toString(36).slice(2, 10)}`;

/**
 * A choice asked in a dialog: resolves with the id of the button pressed (null: dismissed).
 * @param {{title: string, message: string, choices: {id: string, label: string, primary?: boolean}[], testid?: string}} spec
 * @returns {Promise<string | null>}
 */
export function ask(spec) {
  return new Promise((resolve) => {
    studio().setDialog({
      kind: "choice",
      ...spec,
      resolve: (id) => {
        studio().setDialog(null);
        resolve(id);
      },
    });
  });
}

/** A line of text asked in a dialog: resolves with it (null: cancelled). */
export function prompt(spec) {
  return new Promise((resolve) => {
    studio().setDialog({
      kind: "prompt",
      ...spec,
      onOk: (v) => {
        studio().setDialog(null);
        resolve(v);
      },
      onClose: () => {
        studio().setDialog(null);
        resolve(null);
      },
    });
  });
}

function setUrl(path) {
  const url = new URL(window.location.href);
  if (path) url.searchParams.set("open", path);
  else url.searchParams.delete("open");
  url.searchParams.delete("example");
  window.history.replaceState(null, "", url);
}

/** The document with the positions shown written into its layout (what is shown is saved). */
export function withLayout(d, autoPos) {
  const layout = { ...(d.layout || {}) };
  for (const c of d.components || []) {
    const p = autoPos[""] && autoPos[""][c.name];
    if (!layout[c.name] && p) layout[c.name] = { x: Math.round(p.x), y: Math.round(p.y) };
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
}

/** Unsaved changes may be dropped: asks first when there are some; false: keep them. */
async function mayDiscard(action) {
  const s = studio();
  if (!s.isDirty()) return true;
  const name = s.file.path || s.hist.present.name || "the model";
  const choice = await ask({
    title: "Unsaved changes",
    message: `${name} has changes that are not saved. ${action} discards them.`,
    choices: [
      { id: "save", label: "Save first", primary: true },
      { id: "discard", label: "Discard them" },
      { id: "cancel", label: "Cancel" },
    ],
    testid: "confirm-discard",
  });
  if (choice === "discard") {
    // dropped on purpose: its recovery goes too
    api.discardRecovery(s.file.path).catch(() => {});
    return true;
  }
  if (choice === "save") return saveCurrent();
  return false;
}

/** Offer the recovery file of ``path`` (null: the unsaved model) when there is one. */
async function offerRecovery(path) {
  let rec;
  try {
    rec = (await api.recovery(path)).recovery;
  } catch {
    return;
  }
  // a recovery of this page's own work is not "unsaved work from before"
  if (!rec || !rec.model || shapeProblem(rec.model) || rec.session === SESSION) return;
  const s = studio();
  if (path && JSON.stringify(rec.model) === JSON.stringify(s.hist.present)) {
    api.discardRecovery(path).catch(() => {});
    return;
  }
  const when = rec.saved ? new Date(rec.saved).toLocaleString() : "an earlier session";
  const changed = path && rec.base && rec.base !== s.file.version;
  // offered beside the work, not in its way: the page stays usable until it is answered
  s.setOffer({
    path,
    message: `Unsaved changes to ${path || `"${rec.model.name || "untitled"}" (never saved)`} were kept from ${when}.` +
      (changed ? " The file has changed on disk since: saving will ask before overwriting it." : ""),
    recover: () => {
      studio().setOffer(null);
      studio().update(() => rec.model);
      studio().fit();
    },
    discard: () => {
      studio().setOffer(null);
      api.discardRecovery(path).catch(() => {});
    },
  });
}

/** Open a file (``{path}``) or an example (``{example}``), asking first about unsaved work. */
export async function openModel(src, { ask: asking = true } = {}) {
  if (asking && !(await mayDiscard("Opening another model"))) return false;
  const s = studio();
  s.setBusy("Opening…");
  try {
    const r = src.path ? await api.openPath(src.path) : await api.openExample(src.example);
    const bad = shapeProblem(r.model);
    if (bad) {
      s.toast(`cannot show ${src.path || src.example} as a diagram: ${bad}`);
      return false;
    }
    forgetJobs();
    s.setOffer(null);
    s.load(r.model, { path: r.path || null, text: r.text, version: r.version || null, baseline: JSON.stringify(r.model), example: src.example || null });
    s.setDialog(null);
    setUrl(r.path || null);
    if (TESTING) trace.timings.opened = performance.now();
    if (r.path) await offerRecovery(r.path);
    return true;
  } catch (e) {
    s.toast(`cannot open ${src.path || src.example}: ${e.message}`);
    return false;
  } finally {
    s.setBusy(null);
  }
}

/** A new, empty model, asking first about unsaved work. */
export async function newModel() {
  if (!(await mayDiscard("A new model"))) return false;
  forgetJobs();
  const doc = emptyModel();
  studio().load(doc, newFile(doc));
  setUrl(null);
  return true;
}

/** Save to ``path``; ``base``: the version it may replace (default: the one opened). */
export async function saveTo(path, base) {
  const s = studio();
  const dirty = s.isDirty();
  const samePath = path === s.file.path;
  const unchanged = !dirty && samePath && s.file.text != null;
  const doc = s.hist.present;
  const model = unchanged ? doc : withLayout(doc, s.autoPos);
  const version = base !== undefined ? base : samePath ? s.file.version : null;
  s.setBusy("Saving…");
  try {
    const r = await api.save(path, model, unchanged ? s.file.text : null, version);
    let saved = model;
    try {
      saved = JSON.parse(r.text);
    } catch {
      /* keep what was sent */
    }
    const shown = unchanged ? doc : saved;
    const before = s.file.path;
    studio().saved(shown, { path, text: r.text, version: r.version || null, baseline: JSON.stringify(shown), example: null });
    // the work is in the file now: the recovery of where it was before goes too
    if (before !== path) api.discardRecovery(before).catch(() => {});
    setUrl(path);
    const problems = (r.problems || []).length;
    s.toast(`saved ${path} (${r.bytes} bytes)${problems ? `, with ${problems} problem${problems > 1 ? "s" : ""} still to fix before it runs` : ""}`, "info");
    if (TESTING) trace.lastSave = { path, bytes: r.bytes, unchanged, problems };
    return true;
  } catch (e) {
    if (e.status === 409 && e.body && e.body.conflict) return resolveConflict(path, e.body.conflict, e.message);
    s.toast(`cannot save ${path}: ${e.message}`);
    return false;
  } finally {
    s.setBusy(null);
  }
}

/** A save refused because the file on disk is not the one the model was based on: ask. */
async function resolveConflict(path, conflict, message) {
  const exists = conflict.version != null;
  const opened = path === studio().file.path;
  const choice = await ask({
    title: exists ? (opened ? "The file changed on disk" : "The file exists") : "The file was removed",
    message,
    choices: [
      ...(exists && opened ? [{ id: "reload", label: "Reload it (drop my changes)" }] : []),
      { id: "overwrite", label: exists ? "Overwrite it" : "Save it again", primary: !exists },
      { id: "saveas", label: "Save as…", primary: exists },
      { id: "cancel", label: "Cancel" },
    ],
    testid: "conflict",
  });
  if (choice === "reload") {
    api.discardRecovery(path).catch(() => {});
    return openModel({ path }, { ask: false });
  }
  if (choice === "overwrite") return saveTo(path, conflict.version);
  if (choice === "saveas") return saveAs();
  return false;
}

/** Save under a name asked for. */
export async function saveAs() {
  const s = studio();
  const path = await prompt({
    title: "Save as",
    label: "File (relative to the folder the studio was started in)",
    value: s.file.path || `${s.hist.present.name || "model"}.json`,
    testid: "save-path",
  });
  if (path === null || !path.trim()) return false;
  const p = path.trim();
  return saveTo(p.endsWith(".json") ? p : `${p}.json`);
}

/** Save to the file open, or ask for a name. */
export function saveCurrent() {
  const path = studio().file.path;
  return path ? saveTo(path) : saveAs();
}

/**
 * The file work the page does by itself: the model of the URL (and the recovery of an
 * unsaved model) at start, autosave, asking before the tab closes.
 * @param {string | null} openPath the URL's ``open``
 * @param {string | null} example  the URL's ``example``
 */
export function useFiles(openPath, example) {
  const ready = useStudio((s) => !!s.palette);
  const doc = useStudio((s) => s.hist.present);
  const file = useStudio((s) => s.file);
  const dirty = useStudio((s) => JSON.stringify(s.hist.present) !== s.file.baseline);

  useEffect(() => {
    if (!ready) return;
    if (openPath) openModel({ path: openPath }, { ask: false });
    else if (example) openModel({ example }, { ask: false });
    else offerRecovery(null);
  }, [ready, openPath, example]);

  // autosave: the model as it is, beside its file, a moment after the last edit
  useEffect(() => {
    if (!ready || !dirty || file.example) return undefined;
    const id = setTimeout(() => {
      api.autosave(file.path, doc, file.version, SESSION).catch(() => {
        /* a failed autosave is retried on the next edit; the page keeps the model */
      });
    }, AUTOSAVE_MS);
    return () => clearTimeout(id);
  }, [ready, dirty, doc, file]);

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

  const open = useCallback((src) => openModel(src), []);
  return { open, newModel, save: saveCurrent, saveAs, dirty };
}
