// What the end-to-end tests read of the studio (window.__kinetwork), in test builds only:
// `vite build --mode e2e` defines __TEST_HOOK__ as true; in the studio's own build it is
// false, and every `if (TESTING)` block, with this module's trace, is dropped from the bundle.

/** True in a test build (the e2e tests' bundle), false in the studio's own. */
export const TESTING = __TEST_HOOK__;

/**
 * What the tests read besides the store: timings (ms from performance.now()), the last save,
 * what the plots draw (signal -> [t, columns...]) and their axes (title -> a function giving
 * ranges, ticks, labels and sizes), the plot and 3-D view times, the router's last input,
 * the last fit of the diagram (its request, and whether it waits for the wires' routes).
 */
export const trace = TESTING
  ? { timings: {}, lastSave: null, lastRun: null, plotted: {}, plottedSeries: {}, plotAxes: {}, cursorTime: null, plotTime: null, viewer: null, bus: null, wires: null, routing: null, fit: null }
  : null;
