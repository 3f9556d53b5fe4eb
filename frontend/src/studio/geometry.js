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
const TYPE_ROW = 14;
const BODY_MIN = 34;

/** Which way a wire leaves a port on each side. */
export const OUTWARD = { left: [-1, 0], right: [1, 0], top: [0, -1], bottom: [0, 1] };

/**
 * Where each port of a block goes and the block's size. A block turned by ``rotation``
 * degrees has its ports on the sides turned with it; a flipped one has left and right
 * exchanged first. Ports on the left and right sit beside the icon (between the block's name
 * and its type), those on the top and bottom spread along their side.
 *
 * @returns {{handles: {port: any, side: string, x: number, y: number}[], width: number,
 *   height: number}} x, y: a port's place on the block's border from its top left corner
 */
export function blockGeometry(ports, rotation = 0, flip = false) {
  const sides = { left: [], right: [], top: [], bottom: [] };
  for (const p of ports) sides[placedSide(p.side || portSide(p.name, p.domain, ports), rotation, flip)].push(p);
  const tall = Math.max(sides.left.length, sides.right.length);
  const body = Math.max(BODY_MIN, tall * PORT_STEP);
  const height = NAME_ROW + body + TYPE_ROW;
  const ends = Math.max(sides.top.length, sides.bottom.length);
  const width = ends > 2 ? Math.max(BLOCK_W, (ends + 1) * END_STEP) : BLOCK_W;
  const out = [];
  for (const side of ["left", "right"]) {
    const list = sides[side];
    // centred on the body's middle, PORT_STEP apart (whole pixels: the wires run straight)
    const mid = NAME_ROW + body / 2;
    list.forEach((p, i) => out.push({ port: p, side, x: side === "left" ? 0 : width, y: Math.round(mid + (i - (list.length - 1) / 2) * PORT_STEP) }));
  }
  for (const side of ["top", "bottom"]) {
    const list = sides[side];
    list.forEach((p, i) => out.push({ port: p, side, x: Math.round(((i + 1) / (list.length + 1)) * width), y: side === "top" ? 0 : height }));
  }
  return { handles: out, width, height };
}

/** A wire's end at a port: the outer edge of its handle (where React Flow ends it too). */
export function portPoint(nodeX, nodeY, handle) {
  const [dx, dy] = OUTWARD[handle.side];
  return { x: nodeX + handle.x + (dx * HANDLE) / 2, y: nodeY + handle.y + (dy * HANDLE) / 2, dir: [dx, dy] };
}
