// The 3-D viewer's shapes of one kind (boxes, cylinders, spheres, rods, the axes' arrows),
// each kind one InstancedMesh: a unit geometry scaled, placed and coloured per shape; an
// axis is one arrow, shaft and head.
//
// What a frame costs a software renderer (headless Chromium's SwiftShader, a 32-link chain in
// a 403x272 pane): the shapes' triangles and pixels, not the number of draw calls. Measured
// as CPU time of the GPU process a frame, A/B in alternate browser sessions: 6 calls (shafts
// and heads apart) 5.46 ms, 5 calls 5.45 ms; the lit kinds in one call (a shader fetching each
// shape's matrix from a texture) 5.67 against 5.81 ms; each kind's instances merged into one
// mesh moved in JavaScript 5.5 against 5.7 ms, and 1 ms more of the page's time a frame.
import {
  BoxGeometry, Color, ConeGeometry, CylinderGeometry, InstancedMesh, Matrix4,
  MeshBasicMaterial, MeshLambertMaterial, MeshStandardMaterial, Quaternion, SphereGeometry,
  Vector3,
} from "three";
import { mergeGeometries } from "three/examples/jsm/utils/BufferGeometryUtils.js";

const AXIS_COLORS = [0xdc3232, 0x28a03c, 0x3250dc];
const Y = new Vector3(0, 1, 0);
const direction = new Vector3();

const matrix = new Matrix4(), basis = new Matrix4(), turn = new Quaternion();
const scaling = new Vector3(), middle = new Vector3();

// Segments round a shape: as many as its size on screen needs, no more. A polygon of n sides
// round a circle r pixels wide strays r (1 - cos(pi/n)) ~ r pi^2 / 2n^2 from it: under
// TOLERANCE pixels with n >= pi sqrt(r / 2 TOLERANCE). A software renderer (headless
// Chromium's SwiftShader) pays per vertex of every instance: a 32-link chain's cylinders,
// spheres and rods at 32, 14 and 20 segments (12 200 triangles) took 29-31 ms of the GPU
// process a frame, at 12, 8 and 8 (4 264) 15-18 ms, with no difference to see on links
// ten pixels wide.
const TOLERANCE = 0.35;
const STEPS = [6, 8, 10, 12, 16, 20, 24, 32, 48];
// Triangles a kind's instances may take together, however near the camera comes.
const TRIANGLES = 8000;

/**
 * Segments round a kind's shapes: enough for the largest of them, ``radius`` pixels on
 * screen, rounded up to one of a few steps (so zooming rebuilds the geometry seldom), between
 * ``lo`` and ``hi``, and fewer where ``count`` shapes of ``triangles(n)`` triangles each
 * would pass the budget.
 * @param {number} count @param {(n: number) => number} triangles
 * @param {number} lo @param {number} hi @param {number} [radius]
 */
export function segments(count, triangles, lo, hi, radius = Infinity) {
  const need = Math.PI * Math.sqrt(Math.max(radius, 0) / (2 * TOLERANCE));
  const step = STEPS.find(n => n >= need) ?? STEPS[STEPS.length - 1];
  let n = Math.max(lo, Math.min(hi, step));
  while (n > lo && Math.max(count, 1) * triangles(n) > TRIANGLES) n = STEPS.filter(k => k < n).pop() ?? lo;
  return Math.max(lo, n);
}

// Each kind's unit geometry at ``n`` segments round (boxes have none): a shape is this,
// scaled by its sizes, turned into its frame's directions and moved to its place (as `build`
// makes one mesh of its own sizes).
function unitGeometry(kind, n) {
  if (kind === "box") return new BoxGeometry(1, 1, 1).translate(0.5, 0, 0);
  if (kind === "cylinder") return new CylinderGeometry(0.5, 0.5, 1, n).rotateZ(-Math.PI / 2).translate(0.5, 0, 0);
  if (kind === "sphere") return new SphereGeometry(0.5, n, Math.max(3, n >> 1)).translate(0.5, 0, 0);
  if (kind === "rod") return new CylinderGeometry(1, 1, 1, n).translate(0, 0.5, 0);
  // an arrow along y: its shaft and its head, one draw
  return mergeGeometries([new CylinderGeometry(1 / 30, 1 / 30, 0.8, 8).translate(0, 0.4, 0),
                          new ConeGeometry(2.6 / 30, 0.2, 12).translate(0, 0.9, 0)]);
}

// The round kinds: triangles a shape at n segments, the fewest and the most segments
const ROUND = {
  cylinder: [n => 4 * n, 6, 48],
  sphere: [n => n * Math.max(3, n >> 1) * 2, 6, 32],
  rod: [n => 4 * n, 6, 24],
};

// The shapes of one kind, drawn by one InstancedMesh: each on a frame (its matrix there,
// `local`) or, for a rod, between two frames' origins.
class Batch {
  constructor(kind, lit, small = false, soft = false) {
    this.kind = kind;
    this.lit = lit;
    this.small = small;
    this.soft = soft;
    this.items = [];
    this.mesh = null;
  }

  add(item) { this.items.push(item); }

  finish() {
    if (!this.items.length) return null;
    // a software renderer draws Lambert's diffuse light 1.4 times as fast as the physical
    // material (a 32-link chain: 24-27 frames/s against 17-18, drawing only); the picture
    // loses the highlights, which shapes a few pixels wide hardly show
    const paint = !this.lit ? new MeshBasicMaterial({ color: 0xffffff })
      : this.soft ? new MeshLambertMaterial({ color: 0xffffff })
        : new MeshStandardMaterial({ color: 0xffffff, roughness: 0.55, metalness: 0.1 });
    this.segments = this.detail(Infinity);
    const mesh = new InstancedMesh(unitGeometry(this.kind, this.segments), paint, this.items.length);
    this.items.forEach((item, i) => mesh.setColorAt(i, new Color(item.color)));
    // the instances move every frame: a bounding sphere computed once would cull them
    mesh.frustumCulled = false;
    this.mesh = mesh;
    return mesh;
  }

  /** Segments round at ``pixels`` screen pixels a metre (0 for a kind without any). */
  detail(pixels) {
    const round = ROUND[this.kind];
    if (!round) return 0;
    const radius = Math.max(...this.items.map(item => item.radius)) * pixels;
    const [triangles, lo, hi] = round;
    return segments(this.items.length, triangles, lo, hi, radius);
  }

  /** The geometry rebuilt for shapes seen at ``pixels`` screen pixels a metre, if need be. */
  refine(pixels) {
    if (!this.mesh) return;
    const n = this.detail(pixels);
    if (!n || n === this.segments) return;
    this.segments = n;
    this.mesh.geometry.dispose();
    this.mesh.geometry = unitGeometry(this.kind, n);
  }

  update(frames) {
    if (!this.mesh) return;
    this.items.forEach((item, i) => {
      if (item.to !== undefined) {
        const a = frames[item.frame].position;
        direction.subVectors(frames[item.to].position, a);
        const length = direction.length();
        if (length > 1e-12) turn.setFromUnitVectors(Y, direction.divideScalar(length));
        scaling.set(item.radius, length, item.radius);
        matrix.compose(a, turn, length > 1e-12 ? scaling : scaling.setScalar(0));
      } else {
        matrix.multiplyMatrices(frames[item.frame].matrix, item.local);
      }
      this.mesh.setMatrixAt(i, matrix);
    });
    this.mesh.instanceMatrix.needsUpdate = true;
  }

  centers() {
    if (!this.mesh) return [];
    return this.items.map((item, i) => {
      this.mesh.getMatrixAt(i, matrix);
      // the middle of the unit shape (half a length along x, or along y for a rod)
      return (item.to !== undefined ? middle.set(0, 0.5, 0) : middle.set(0.5, 0, 0)).applyMatrix4(matrix).toArray();
    });
  }
}

/** A batch for each kind; ``soft``: drawn by a software renderer. */
export function makeBatches(soft) {
  return {
    box: new Batch("box", true, false, soft), cylinder: new Batch("cylinder", true, false, soft),
    sphere: new Batch("sphere", true, false, soft), rod: new Batch("rod", true, false, soft),
    arrow: new Batch("arrow", false), frameArrow: new Batch("arrow", false, true),
  };
}

/** Put ``shape`` in its kind's batch; false for what is drawn on its own (springs, mesh
 * files, the ground's grid). ``small``: a frame's own axes, which the "frames" button hides. */
export function batched(shape, batches, small) {
  const kind = shape.kind;
  if (kind === "box" || kind === "cylinder" || kind === "sphere") {
    const { length, width, height } = shape;
    const l = new Vector3().fromArray(shape.length_direction);
    const w = new Vector3().fromArray(shape.width_direction);
    basis.makeBasis(l, w, new Vector3().crossVectors(l, w));
    const sizes = kind === "box" ? [length, width, height] : kind === "cylinder" ? [length, width, width] : [length, length, length];
    const local = new Matrix4().compose(new Vector3().fromArray(shape.r_shape),
                                        new Quaternion().setFromRotationMatrix(basis),
                                        new Vector3(...sizes));
    // the radius round the length: what a round kind's segments go round
    batches[kind].add({ frame: shape.frame, local, color: shape.color, radius: (kind === "sphere" ? length : width) / 2 });
    return true;
  }
  if (kind === "rod") {
    batches.rod.add({ frame: shape.frame, to: shape.to, radius: shape.diameter / 2, color: shape.color });
    return true;
  }
  if (kind === "axes") {
    const arrows = small ? batches.frameArrow : batches.arrow;
    [new Vector3(1, 0, 0), Y, new Vector3(0, 0, 1)].forEach((d, k) => {
      const local = new Matrix4().compose(new Vector3(), new Quaternion().setFromUnitVectors(Y, d),
                                          new Vector3(shape.length, shape.length, shape.length));
      arrows.add({ frame: shape.frame, local, color: AXIS_COLORS[k] });
    });
    return true;
  }
  return false;
}
