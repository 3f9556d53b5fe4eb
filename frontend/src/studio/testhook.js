// window.__kinetwork: the end-to-end tests' view of the store (getters, always current) and
// a few handles (the 3-D viewer, the plots' time). Installed by main.jsx in test builds only.
import { trace } from "./testing.js";

/** @param {import("zustand").StoreApi<any>} store */
export function installTestHook(store) {
  const K = {};
  const get = () => store.getState();
  const view = {
    doc: () => get().hist.present,
    file: () => get().file,
    dirty: () => get().isDirty(),
    validation: () => get().validation,
    validated: () => get().validation.doc === get().hist.present,
    runState: () => get().run,
    runs: () => get().runs,
    /** the 3-D view of the run i (latest first), whether it came with its results or after */
    views: () => get().views,
    scopes: () => get().scopes,
    selection: () => get().selection,
    dialog: () => get().dialog,
    history: () => ({ past: get().hist.past.length, future: get().hist.future.length }),
    timings: () => trace.timings,
    lastRun: () => trace.lastRun,
    plotted: () => trace.plotted,
    plottedSeries: () => trace.plottedSeries,
    plotAxes: () => Object.fromEntries(Object.entries(trace.plotAxes).map(([k, read]) => [k, read()])),
    cursorTime: () => trace.cursorTime,
    wires: () => trace.wires,
    /** the wires drawn are routed for the diagram as shown (no routing outstanding) */
    routed: () => !!trace.wires && trace.wires.asked === trace.wires.answered,
    /** the diagram shown is fitted as its opening (or the fit button) asked, wires included,
     * to the pane as it is now (a new window size refits a view the user has not moved) */
    fitted: () => {
      const f = trace.fit;
      const pane = document.querySelector('[data-testid="canvas"]');
      return !!f && !!pane && f.request === get().fitRequest && !f.wires && !!f.pane && f.pane[0] === pane.clientWidth && f.pane[1] === pane.clientHeight;
    },
  };
  for (const [key, read] of Object.entries(view)) Object.defineProperty(K, key, { get: read, enumerable: true });
  Object.defineProperty(K, "lastSave", {
    get: () => trace.lastSave,
    set: (v) => {
      trace.lastSave = v;
    },
  });
  Object.defineProperty(K, "plotTime", {
    get: () => trace.plotTime,
    set: (v) => {
      trace.plotTime = v;
    },
  });
  K.store = store;
  K.viewer = () => trace.viewer;
  /** the animation of the run i (latest first), or null while it is on its way */
  K.animationOf = (i) => {
    const run = get().runs[i];
    if (!run) return null;
    return run.results.animation_pending ? (get().views[run.id] || {}).animation || null : run.results.animation;
  };
  /** answers of the routing worker held back (true) or delivered (false) */
  K.holdRouting = (on) => trace.routing.hold(on);
  K.setTime = (t) => {
    if (trace.bus) trace.bus.setTime(t);
    if (trace.viewer) trace.viewer.setTime(t);
  };
  /** @type {any} */ (window).__kinetwork = K;
}
