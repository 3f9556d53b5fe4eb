// The page's panes: the palette, the side panel (parameters, JSON, analysis), the results
// (plots and 3-D view) under the diagram, and the 3-D view beside the plots. Each can be
// resized by its splitter and collapsed; the sizes the user chose are kept in the browser's
// storage (zustand's persist), so the studio opens as it was left. A size never chosen
// follows the window, and every size is clamped to the room there is, so the page fits at
// 1000x700 as at 1920x1080.
import { create } from "zustand";
import { createJSONStorage, persist } from "zustand/middleware";

/** @typedef {"palette" | "side" | "results" | "viewer"} PaneName */

/** The panes, with how each is measured: along x or y, its bounds (px) and its default. */
export const PANES = {
  palette: { axis: "x", min: 150, max: 0.3, initial: (room) => clamp(0.17 * room, 170, 240) },
  side: { axis: "x", min: 230, max: 0.4, initial: (room) => clamp(0.22 * room, 250, 330) },
  results: { axis: "y", min: 150, max: 0.75, initial: (room) => 0.36 * room },
  viewer: { axis: "x", min: 200, max: 0.7, initial: (room) => 0.4 * room },
};
/** The diagram and the plots keep at least this much room (px). */
export const KEEP = { x: 320, y: 160 };
export const SPLITTER = 7;

export function clamp(v, lo, hi) {
  return Math.min(Math.max(v, lo), Math.max(lo, hi));
}

/**
 * A pane's size on screen: the user's (or the default for ``room``), within its bounds and
 * leaving ``KEEP`` to its neighbour; 0 when collapsed.
 * @param {PaneName} name
 * @param {{size: Record<string, number | null>, closed: Record<string, boolean>}} state
 * @param {number} room the length of what the pane shares with its neighbour (px)
 * @param {number} taken what other panes already take of ``room`` (px)
 */
export function paneSize(name, state, room, taken = 0) {
  if (state.closed[name]) return 0;
  const pane = PANES[name];
  const want = state.size[name] ?? pane.initial(room);
  const keep = KEEP[pane.axis] + taken;
  return Math.round(clamp(want, pane.min, Math.min(pane.max * room, room - keep)));
}

export const usePanes = create(
  persist(
    (set) => ({
      /** sizes chosen by the user (px), null where never chosen */
      size: /** @type {Record<PaneName, number | null>} */ ({ palette: null, side: null, results: null, viewer: null }),
      closed: /** @type {Record<PaneName, boolean>} */ ({ palette: false, side: false, results: false, viewer: false }),
      /** @param {PaneName} name @param {number} px */
      resize: (name, px) => set((s) => ({ size: { ...s.size, [name]: Math.round(px) }, closed: { ...s.closed, [name]: false } })),
      /** @param {PaneName} name */
      toggle: (name) => set((s) => ({ closed: { ...s.closed, [name]: !s.closed[name] } })),
    }),
    {
      name: "kinetwork.studio.panes",
      storage: createJSONStorage(() => window.localStorage),
      partialize: (s) => ({ size: s.size, closed: s.closed }),
      version: 1,
    },
  ),
);
