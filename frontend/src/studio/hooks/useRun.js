// Runs and sweeps: start one on the server, follow its progress, cancel it, keep what it
// computed. Cancel shows "cancelling" at once; whatever the server kept (the run up to where
// it stopped) is plotted, marked partial. One job at a time, for the model now open.
import { useCallback } from "react";
import { api } from "../api.js";
import { cursorSinceRun, studio, useStudio } from "../store.js";
import { TESTING, trace } from "../testing.js";
import { runLabel } from "../runs.js";

/** Runs overlaid in the plots besides the latest. */
export const OVERLAY = 3;
// each poll waits on the server for the run's end (the page hears of it at once), at most
// this long, so that the progress shown moves on meanwhile
const POLL_WAIT_S = 0.25;
const POLL_CANCELLING_MS = 40;

let timer = null;
let generation = 0;

function stop() {
  if (timer) clearTimeout(timer);
  timer = null;
  generation++;
}

/** Forget any job being followed (another model opened). */
export function forgetJobs() {
  stop();
}

function isGoing(run) {
  return !!run && ["starting", "running", "cancelling"].includes(run.state);
}

/** Follow job ``id`` until it ends; ``kind`` "run" or "sweep"; ``meta`` goes with its results. */
function follow(id, kind, meta, started) {
  const mine = generation;
  const tick = async () => {
    let st;
    try {
      const wait = studio().run && studio().run.state === "cancelling" ? 0 : POLL_WAIT_S;
      st = kind === "sweep" ? await api.sweepStatus(id, wait) : await api.runStatus(id, wait);
    } catch (e) {
      if (mine !== generation) return;
      useStudio.setState({ run: { id, kind, state: "failed", progress: 0, error: e.message, problems: e.problems } });
      studio().toast(e.message);
      return;
    }
    if (mine !== generation) return;
    const now = studio().run;
    if (st.state === "running") {
      const cancelling = now && now.state === "cancelling";
      useStudio.setState({ run: { id, kind, state: cancelling ? "cancelling" : "running", progress: st.progress || 0, phase: st.phase || null } });
      timer = setTimeout(tick, cancelling ? POLL_CANCELLING_MS : 0);
      return;
    }
    timer = null;
    finish(id, kind, st, meta, started);
  };
  timer = setTimeout(tick, 0);
}

function finish(id, kind, st, meta, started) {
  const s = studio();
  useStudio.setState({ run: { id, kind, state: st.state, progress: st.state === "done" ? 1 : st.progress || 0, error: st.error, problems: st.problems || [], phase: st.phase || null } });
  const results = st.results;
  const members = st.members;
  const hasResults = kind === "sweep" ? members && members.some((m) => m.results && m.results.t.length) : results && results.t && results.t.length;
  if (hasResults) {
    const n = s.runCount + 1;
    const entry = { n, id, kind, state: st.state, results: kind === "sweep" ? null : results, members: kind === "sweep" ? members : null, meta };
    entry.label = runLabel(entry, s.runs[0]);
    cursorSinceRun.t = null;             // its plots are drawn afresh, without a cursor
    useStudio.setState((x) => ({ runCount: n, runs: [entry, ...x.runs].slice(0, OVERLAY + 1) }));
    if (kind === "run" && results.animation_pending) fetchView(id);
    if (TESTING) {
      trace.lastRun = results || (members && members[0] && members[0].results);
      trace.timings.runDone = performance.now();
      trace.timings.runSeconds = (trace.timings.runDone - started) / 1000;
    }
  }
  const what = kind === "sweep" ? "the sweep" : "the run";
  if (st.state === "failed") s.toast(`${what} failed: ${st.error || "no reason given"}`);
  else if (st.state === "cancelled") {
    s.toast(hasResults ? `${what} was cancelled: the plots show what it computed (partial)` : `${what} was cancelled before it computed anything${st.phase ? ` (it was ${st.phase})` : ""}`, "info");
  }
}

// a 3-D view asked for once its run's results came ahead of it: how long it is waited for
const VIEW_WAIT_S = 2;
const VIEW_TRIES = 60;

/** The 3-D view of run ``id``, whose results came ahead of it, into ``views`` (the plots are
 * not drawn again). Followed until it comes, the run is forgotten or another model opens. */
async function fetchView(id) {
  const runsNow = () => studio().runs;
  for (let i = 0; i < VIEW_TRIES && runsNow().some((r) => r.id === id); i++) {
    let st;
    try {
      st = await api.runView(id, VIEW_WAIT_S);
    } catch (e) {
      st = { state: "failed", animation: null, animation_note: `The 3-D view could not be had: ${e.message}` };
    }
    if (st.state === "running") continue;
    if (!runsNow().some((r) => r.id === id)) return;
    useStudio.setState((x) => ({ views: { ...pruned(x.views, x.runs), [id]: { animation: st.animation || null, note: st.animation_note || null } } }));
    return;
  }
}

/** ``views`` of the runs still kept. */
function pruned(views, runs) {
  return Object.fromEntries(Object.entries(views).filter(([id]) => runs.some((r) => r.id === id)));
}

/** What a run is given of the model: its parameter values, to label it beside others. */
function snapshot(doc) {
  return { parameters: { ...(doc.parameters || {}) }, components: doc.components || [] };
}

/**
 * Run, sweep and cancel.
 * @returns {{run: () => Promise<void>, sweep: (spec: any) => Promise<void>, cancel: () => Promise<void>, going: boolean}}
 */
export function useRun() {
  const going = useStudio((s) => isGoing(s.run));

  const start = useCallback(async (kind, post) => {
    if (isGoing(studio().run)) return;
    stop();
    const started = performance.now();
    if (TESTING) trace.timings.runClicked = started;
    const doc = studio().hist.present;
    useStudio.setState({ run: { kind, state: "starting", progress: 0 } });
    let id;
    try {
      const r = await post(doc, studio().file.path);
      id = kind === "sweep" ? r.sweep : r.run;
    } catch (e) {
      useStudio.setState({ run: { kind, state: "failed", progress: 0, error: e.message, problems: e.problems } });
      studio().toast(`cannot ${kind}: ${e.message}`);
      return;
    }
    const now = studio().run;
    if (now && now.state === "cancelling") {
      // cancelled before the server named the job: cancel it now
      api.cancel(kind, id).catch(() => {});
    }
    useStudio.setState({ run: { id, kind, state: now && now.state === "cancelling" ? "cancelling" : "running", progress: 0 } });
    follow(id, kind, snapshot(doc), started);
  }, []);

  const run = useCallback(() => start("run", (doc, path) => api.run(doc, {}, path)), [start]);
  const sweep = useCallback((spec) => start("sweep", (doc, path) => api.sweep(doc, spec, path)), [start]);

  const cancel = useCallback(async () => {
    const now = studio().run;
    if (!isGoing(now) || now.state === "cancelling") return;
    // shown at once, before the server answers
    useStudio.setState({ run: { ...now, state: "cancelling" } });
    if (!now.id) return;
    try {
      await api.cancel(now.kind || "run", now.id);
    } catch (e) {
      studio().toast(e.message);
    }
  }, []);

  return { run, sweep, cancel, going };
}
