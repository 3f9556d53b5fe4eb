// Where a block's ports are, in pixels of the diagram at zoom 1: shared by the block's drawing
// (its handles and their names) and the wire router (where each wire starts and ends), so the
// two never disagree.
import { placedSide, portSide } from "./model.js";

export const BLOCK_W = 116;
/** Pixels between neighbouring ports on a side. */
export const PORT_STEP = 20;
/** Pixels between ports on the top or bottom when there are more than two (room for names). */
const END_STEP = 40;
/** A handle's size: big enough to hit with the mouse. */
export const HANDLE = 14;
const NAME_ROW = 16;
/** The icon's room between the names of the ports on the left and on the right. */
const ICON_W = 36;
/** The widest a port's name is shown inside its block (a longer one ends in "..."). */
const LABEL_MAX = 120;
const TYPE_ROW = 14;
const BODY_MIN = 34;

/**
 * How wide a port's name is drawn (px, 8.5 px type): thin letters, wide ones, capitals and the
 * rest, a tenth over Arial's (Inter, the studio's first face, is about that much wider). An
 * estimate, not a measure, so that a block's size never depends on the fonts installed.
 */
export function labelWidth(name) {
  let w = 3;
  for (const ch of String(name)) w += /[fijlrtI.,:;'|!()[\]-]/.test(ch) ? 2.8 : /[mwMW]/.test(ch) ? 7.8 : /[A-Z]/.test(ch) ? 6.4 : 5.2;
  return Math.min(LABEL_MAX, Math.ceil(w));
}

/** Which way a wire leaves a port on each side. */
export const OUTWARD = { left: [-1, 0], right: [1, 0], top: [0, -1], bottom: [0, 1] };

/**
 * Where each port of a block goes and the block's size. A block turned by ``rotation``
 * degrees has its ports on the sides turned with it; a flipped one has left and right
 * exchanged first. Ports on the left and right sit beside the icon (between the block's name
 * and its type), those on the top and bottom spread along their side. A block is as wide as
 * the names of its ports on the left and right beside its icon need (a subsystem's
 * ``shoulder_frame_b``), at least BLOCK_W.
 *
 * @returns {{handles: {port: any, side: string, x: number, y: number, room: number}[],
 *   width: number, height: number, labels: {left: number, right: number}}} x, y: a port's
 *   place on the block's border from its top left corner; room: how wide its name may be
 *   drawn; labels: the room of the names on the left and right
 */
export function blockGeometry(ports, rotation = 0, flip = false) {
  const sides = { left: [], right: [], top: [], bottom: [] };
  for (const p of ports) sides[placedSide(p.side || portSide(p.name, p.domain, ports), rotation, flip)].push(p);
  const tall = Math.max(sides.left.length, sides.right.length);
  const body = Math.max(BODY_MIN, tall * PORT_STEP);
  const height = NAME_ROW + body + TYPE_ROW;
  const ends = Math.max(sides.top.length, sides.bottom.length);
  const labels = { left: 0, right: 0 };
  for (const side of ["left", "right"]) for (const p of sides[side]) labels[side] = Math.max(labels[side], labelWidth(p.name));
  // the names side by side with the icon between; even, so the middle is a whole pixel
  const named = 2 * Math.ceil((labels.left + labels.right + ICON_W) / 2);
  const width = Math.max(BLOCK_W, named, ends > 2 ? (ends + 1) * END_STEP : 0);
  const out = [];
  for (const side of ["left", "right"]) {
    const list = sides[side];
    // centred on the body's middle, PORT_STEP apart (whole pixels: the wires run straight)
    const mid = NAME_ROW + body / 2;
    list.forEach((p, i) => out.push({ port: p, side, x: side === "left" ? 0 : width, y: Math.round(mid + (i - (list.length - 1) / 2) * PORT_STEP), room: labels[side] }));
  }
  for (const side of ["top", "bottom"]) {
    const list = sides[side];
    // a name beside its port, outwards: as far as the next port or the block's corner
    const room = Math.max(40, Math.floor(width / (list.length + 1)) - HANDLE / 2 - 1);
    list.forEach((p, i) => out.push({ port: p, side, x: Math.round(((i + 1) / (list.length + 1)) * width), y: side === "top" ? 0 : height, room }));
  }
  return { handles: out, width, height, labels };
}

/** A wire's end at a port: the outer edge of its handle (where React Flow ends it too). */
export function portPoint(nodeX, nodeY, handle) {
  const [dx, dy] = OUTWARD[handle.side];
  return { x: nodeX + handle.x + (dx * HANDLE) / 2, y: nodeY + handle.y + (dy * HANDLE) / 2, dir: [dx, dy] };
}
