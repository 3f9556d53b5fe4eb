// The view that shows a whole diagram: as large as the pane allows with none of it under
// what floats over the pane's corners; and whether the minimap's corner is free of blocks (at
// 1400x900 a plain fit put a 32-link chain's last row under it).

/** Pixels kept clear round the diagram and between it and a corner's control. */
export const MARGIN = 12;

/**
 * @typedef {{x: number, y: number, width: number, height: number}} Rect
 * @param {Rect} bounds the diagram's extent (its coordinates)
 * @param {{width: number, height: number}} pane the pane's size (px)
 * @param {Rect[]} controls what floats over the pane (px, from its top left corner)
 * @param {number} maxZoom
 * @param {number} minZoom
 * @param {Rect[]} [blocks] the blocks (the diagram's coordinates): a control may lie over the
 *   diagram's empty corner, not over one of these (default: over none of its extent)
 * @returns {{x: number, y: number, zoom: number}} the viewport: screen = diagram * zoom + (x, y)
 */
export function fitViewport(bounds, pane, controls, maxZoom, minZoom, blocks = [bounds]) {
  const { width: W, height: H } = pane;
  // the room each way: the whole pane; the pane above the lowest control's top (the controls
  // sit in the bottom corners); the pane between the controls' inner edges
  const top = Math.min(H, ...controls.map((c) => c.y));
  const left = Math.max(0, ...controls.filter((c) => c.x + c.width / 2 < W / 2).map((c) => c.x + c.width));
  const right = Math.min(W, ...controls.filter((c) => c.x + c.width / 2 >= W / 2).map((c) => c.x));
  const areas = [
    { x: 0, y: 0, width: W, height: H },
    { x: 0, y: 0, width: W, height: top },
    { x: left, y: 0, width: right - left, height: H },
  ];
  let best = null;
  for (const area of areas) {
    const view = within(bounds, area, maxZoom, minZoom);
    if (!view) continue;
    const clear = blocks.every((b) => {
      const shown = { x: b.x * view.zoom + view.x, y: b.y * view.zoom + view.y, width: b.width * view.zoom, height: b.height * view.zoom };
      return controls.every((c) => !overlap(shown, c));
    });
    if (clear && (!best || view.zoom > best.zoom)) best = view;
  }
  // nothing clear of them (a pane smaller than its controls): the plain fit
  return best || within(bounds, { x: 0, y: 0, width: W, height: H }, maxZoom, minZoom) || { x: 0, y: 0, zoom: 1 };
}

/** The diagram centred in ``area`` with MARGIN round it; null where there is no room. */
function within(bounds, area, maxZoom, minZoom) {
  const w = area.width - 2 * MARGIN;
  const h = area.height - 2 * MARGIN;
  if (w <= 0 || h <= 0) return null;
  const fit = Math.min(w / Math.max(bounds.width, 1), h / Math.max(bounds.height, 1));
  const zoom = Math.max(minZoom, Math.min(maxZoom, fit));
  return {
    zoom,
    x: area.x + MARGIN + (w - bounds.width * zoom) / 2 - bounds.x * zoom,
    y: area.y + MARGIN + (h - bounds.height * zoom) / 2 - bounds.y * zoom,
  };
}

/** Diagram pixels kept round a wire's line: its stroke and the arrowhead of a signal wire. */
export const WIRE_PAD = 8;

/**
 * What a fitted view must hold: the blocks' bounds, the parts drawn outside them (ports,
 * port names, badges) and every wire's path (a wire may run round the outside of the blocks,
 * above the top one); the diagram's coordinates.
 * @param {Rect} blocks
 * @param {Rect[]} parts
 * @param {{x: number, y: number}[][]} wires each wire's points
 * @returns {Rect}
 */
export function diagramExtent(blocks, parts, wires) {
  let x0 = blocks.x;
  let y0 = blocks.y;
  let x1 = blocks.x + blocks.width;
  let y1 = blocks.y + blocks.height;
  for (const r of parts) {
    x0 = Math.min(x0, r.x);
    y0 = Math.min(y0, r.y);
    x1 = Math.max(x1, r.x + r.width);
    y1 = Math.max(y1, r.y + r.height);
  }
  for (const points of wires) {
    for (const p of points) {
      x0 = Math.min(x0, p.x - WIRE_PAD);
      y0 = Math.min(y0, p.y - WIRE_PAD);
      x1 = Math.max(x1, p.x + WIRE_PAD);
      y1 = Math.max(y1, p.y + WIRE_PAD);
    }
  }
  return { x: x0, y: y0, width: x1 - x0, height: y1 - y0 };
}

/** Whether rectangles ``a`` and ``b`` overlap. */
function overlap(a, b) {
  return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
}

/** Where React Flow puts the minimap (bottom right, 15 px in) in a pane of ``size``. */
export function minimapBox(size, map = { width: 140, height: 90 }) {
  return { x: size.width - 15 - map.width, y: size.height - 15 - map.height, width: map.width, height: map.height };
}

/** Whether ``box`` (pane px) lies over one of ``blocks`` (diagram coordinates) in ``view``. */
export function covers(view, blocks, box) {
  return blocks.some((b) => overlap({ x: b.x * view.zoom + view.x, y: b.y * view.zoom + view.y, width: b.width * view.zoom, height: b.height * view.zoom }, box));
}
