// The 3-D viewer of a kinetwork Animation (kinetwork.animation.animation_data): the scene's
// shapes on their frames, the frames moved along their poses in time.
//
//   const viewer = createViewer(element, animation, {controls: true, onTime: t => ...});
//   viewer.setTime(1.5); viewer.play(); viewer.pause(); viewer.setSpeed(0.5); viewer.dispose();
//
// Options: controls (draw play/pause, scrub, time, speed, frames and view buttons; default
// false), onTime(t) (called ten times a second while playing, on pause and when the user
// scrubs; not on setTime), autoplay (default false), loop (default true), speed (default 1),
// showFrames (the small axes on every frame; default: when there are at most 24). Between samples positions are interpolated
// linearly and orientations along the shorter arc, so any grid plays smoothly at any speed.
// Besides: getTime(), isPlaying(), renderInfo() (the last frame's draw calls and triangles,
// the renderer's name, whether it multisamples (not on a software renderer) and the pixel
// ratio, which playing lowers while frames come slowly and fewer pixels make them faster),
// centers(kind) (where each body shape of a kind is: its frame's pose applied to its middle).
//
// Shapes of one kind (boxes, cylinders, spheres, rods, axes' arrows) are drawn as one
// InstancedMesh (batches.js), so a chain of 32 links costs a handful of draw calls instead of
// one per shape.
import {
  AmbientLight, BufferGeometry, Color, DirectionalLight, Float32BufferAttribute, GridHelper,
  Group, Mesh, MeshStandardMaterial, PerspectiveCamera, Quaternion, Scene, TubeGeometry, Curve,
  Vector2, Vector3, WebGLRenderer,
} from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { batched, makeBatches } from "./batches.js";

export { segments } from "./batches.js";

const SPEEDS = [0.1, 0.25, 0.5, 1, 2, 4];
const FRAMES_SHOWN = 24;
/** ms between updates of the time in the bar while playing */
const LABEL_MS = 100;
const Y = new Vector3(0, 1, 0);
/** The names WebGL gives a renderer without a GPU behind it. */
const SOFTWARE = /SwiftShader|llvmpipe|softpipe|Software/i;

// What draws WebGL here ("ANGLE (Google, Vulkan 1.3.0 (SwiftShader Device ...))"), asked of a
// context made for the question and let go at once; "" where the browser does not say.
function rendererName() {
  try {
    const gl = document.createElement("canvas").getContext("webgl2");
    if (!gl) return "";
    const info = gl.getExtension("WEBGL_debug_renderer_info");
    const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : String(gl.getParameter(gl.RENDERER));
    const lose = gl.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return name;
  } catch {
    return "";
  }
}

export function createViewer(element, animation, options = {}) {
  const data = prepare(animation);
  const root = document.createElement("div");
  root.className = "kn-viewer";
  root.tabIndex = 0;
  element.appendChild(root);
  injectStyle();

  const state = { time: data.t[0], playing: false, speed: options.speed || 1, last: null,
                  frame: 0, pending: 0, shown: -Infinity, disposed: false };
  let renderer;
  const gpu = rendererName();
  // The picture goes to the page through an OffscreenCanvas where the browser has one: its
  // frames reach the compositor directly, so a frame drawn asks nothing of the page's own
  // paint (a canvas of the page re-layers the whole document at every frame: ~4 ms beside a
  // diagram of a hundred blocks in headless Chromium, and the software compositor's
  // read-back of the picture waits on the main thread).
  const canvas = document.createElement("canvas");
  try {
    const offscreen = typeof canvas.transferControlToOffscreen === "function"
      ? canvas.transferControlToOffscreen() : null;
    // multisampling doubles a software renderer's frame time (a 32-link chain in headless
    // Chromium's SwiftShader: 7.6 frames/s with it, 13.6 without); a GPU does it for free
    renderer = new WebGLRenderer({ canvas: offscreen || canvas, antialias: !SOFTWARE.test(gpu) });
  } catch (err) {
    const note = document.createElement("div");
    note.className = "kn-viewer-note";
    note.textContent = "This 3-D view needs WebGL, which this browser does not offer.";
    root.appendChild(note);
    console.warn("kinetwork viewer:", err);
    return stub(root, data, state);
  }
  const pixels = new PixelBudget(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setPixelRatio(pixels.ratio);
  root.appendChild(canvas);

  const scene = new Scene();
  scene.background = new Color(0xf4f5f7);
  const camera = new PerspectiveCamera(animation.view.fov || 35, 1, 0.01, 1000);
  camera.up.fromArray(animation.view.up);
  camera.add(new DirectionalLight(0xffffff, 2.2).translateX(-0.4).translateY(0.6).translateZ(1));
  scene.add(camera, new AmbientLight(0xffffff, 1.1));

  const frames = data.frames.map(() => {
    const group = new Group();
    scene.add(group);
    return group;
  });
  const links = [];      // shapes between two frames, rebuilt from their origins
  const frameAxes = [];  // what the "frames" button shows and hides
  const ground = animation.shapes.find(s => s.kind === "grid");
  const batches = makeBatches(SOFTWARE.test(gpu));
  let framesWithAxes = 0;
  for (const shape of animation.shapes) {
    const small = shape.kind === "axes" && shape.component === null
      && !(ground && shape.frame === ground.frame);
    if (small) framesWithAxes++;
    if (batched(shape, batches, small)) continue;
    const object = build(shape);
    if (!object) continue;
    if (shape.kind === "spring") {
      scene.add(object);
      links.push({ shape, object });
    } else {
      frames[shape.frame].add(object);
    }
  }
  for (const batch of Object.values(batches)) {
    const mesh = batch.finish();
    if (!mesh) continue;
    scene.add(mesh);
    if (batch.small) frameAxes.push(mesh);
  }

  const controls = new OrbitControls(camera, canvas);
  controls.addEventListener("change", () => { refine(); request(); });

  const ui = options.controls ? buildControls() : null;
  const resize = new ResizeObserver(() => layout());
  resize.observe(root);
  layout();
  fitView();
  // a scene of many frames (an engine) is clearer without them until asked for
  setFramesVisible(options.showFrames ?? framesWithAxes <= FRAMES_SHOWN);
  apply(state.time);
  const onKey = event => {
    if (event.code === "Space") { event.preventDefault(); state.playing ? pause() : play(); }
  };
  root.addEventListener("keydown", onKey);
  if (options.autoplay) play(); else request();

  // -- time ---------------------------------------------------------------------------------
  function apply(time) {
    const t = data.t, n = t.length;
    let i = 0, w = 0;
    if (n > 1) {
      let lo = 0, hi = n - 1;
      while (hi - lo > 1) {
        const mid = (lo + hi) >> 1;
        if (t[mid] <= time) lo = mid; else hi = mid;
      }
      i = lo;
      w = t[hi] > t[lo] ? Math.min(Math.max((time - t[lo]) / (t[hi] - t[lo]), 0), 1) : 0;
    }
    for (let k = 0; k < frames.length; k++) {
      pose(data.frames[k], i, w, frames[k]);
      frames[k].updateMatrix();
    }
    for (const { shape, object } of links) stretch(object, frames[shape.frame].position,
                                                   frames[shape.to].position);
    for (const batch of Object.values(batches)) batch.update(frames);
  }

  function setTime(time, fromUser = false) {
    state.time = clampTime(time);
    apply(state.time);
    if (ui) ui.show(state.time);
    if (fromUser && options.onTime) options.onTime(state.time);
    request();
  }

  function clampTime(time) {
    const t = data.t;
    return Math.min(Math.max(Number(time) || 0, t[0]), t[t.length - 1]);
  }

  function tick(now) {
    state.frame = 0;
    if (state.disposed) return;
    if (state.playing) {
      const t = data.t, span = t[t.length - 1] - t[0];
      if (state.last !== null) state.time += (now - state.last) / 1000 * state.speed;
      state.last = now;
      if (state.time > t[t.length - 1]) {
        if (options.loop === false || span <= 0) { state.time = t[t.length - 1]; pause(); }
        else state.time = t[0] + (state.time - t[0]) % span;
      }
      apply(state.time);
      // the time in the bar and the host's (the plots' cursors) change ten times a second,
      // together, not every frame: any change of the page repaints and re-layers the whole
      // document (beside a diagram of a hundred blocks: ~15 ms a frame in headless Chromium);
      // the bar is a layer of its own (will-change), so the label's change is not laid into
      // the page's layers again (a frame that moves it: layerization 2.0-2.5 -> 1.0 ms)
      if (now - state.shown >= LABEL_MS) {
        state.shown = now;
        if (ui) ui.show(state.time);
        if (options.onTime) options.onTime(state.time);
      }
      if (pixels.frame(now)) {
        renderer.setPixelRatio(pixels.ratio);
        layout();
      }
    }
    renderer.render(scene, camera);
    if (state.playing) request();
  }

  function request() {
    if (!state.frame && !state.disposed) state.frame = requestAnimationFrame(tick);
  }

  function play() {
    const t = data.t;
    if (state.time >= t[t.length - 1] && options.loop === false) state.time = t[0];
    state.playing = true;
    state.last = null;
    pixels.restart();
    if (ui) ui.playing(true);
    request();
  }

  function pause() {
    const was = state.playing;
    state.playing = false;
    state.shown = -Infinity;
    if (ui) { ui.playing(false); ui.show(state.time); }
    if (was && options.onTime) options.onTime(state.time);
    request();
  }

  function setSpeed(speed) {
    if (!(speed > 0)) return;
    state.speed = speed;
    if (ui) ui.speed(speed);
  }

  // -- view ---------------------------------------------------------------------------------
  function layout() {
    const width = root.clientWidth || 640;
    const height = Math.max((root.clientHeight || 480) - (ui ? ui.height() : 0), 50);
    // the drawing buffer's size; the page's canvas is sized here (an OffscreenCanvas has no style)
    renderer.setSize(width, height, false);
    canvas.style.width = `${width}px`;
    canvas.style.height = `${height}px`;
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    refine();
    request();
  }

  // The round shapes' segments for their size on screen now: screen pixels a metre at the
  // model's nearest part (the camera's distance to its target, less half the model's size).
  function refine() {
    const distance = camera.position.distanceTo(controls.target);
    const near = Math.max(distance - data.scale / 2, distance / 4, 1e-9);
    const size = renderer.getDrawingBufferSize(drawing);
    const pixels = size.y / 2 / (near * Math.tan(camera.fov * Math.PI / 360));
    for (const batch of Object.values(batches)) batch.refine(pixels);
  }

  function fitView() {
    const view = animation.view;
    const target = new Vector3().fromArray(view.target);
    const forward = new Vector3().fromArray(view.direction).negate().normalize();
    const up = new Vector3().fromArray(view.up);
    const right = new Vector3().crossVectors(forward, up).normalize();
    const camUp = new Vector3().crossVectors(right, forward);
    const tan = Math.tan((view.fov || 35) * Math.PI / 360);
    const aspect = Math.min(Math.max(camera.aspect || 1, 0.3), 3);
    const margin = data.scale / 5;
    const [lo, hi] = animation.bounds;
    let distance = data.scale * 0.5;
    for (const x of [lo[0] - margin, hi[0] + margin])
      for (const y of [lo[1] - margin, hi[1] + margin])
        for (const z of [lo[2] - margin, hi[2] + margin]) {
          const c = new Vector3(x, y, z).sub(target);
          const depth = c.dot(forward);
          distance = Math.max(distance, Math.abs(c.dot(camUp)) / tan - depth,
                              Math.abs(c.dot(right)) / (tan * aspect) - depth);
        }
    distance *= 1.08;
    camera.position.copy(target).addScaledVector(forward, -distance);
    camera.near = distance / 200;
    camera.far = distance * 50;
    camera.updateProjectionMatrix();
    controls.target.copy(target);
    controls.update();
    refine();
    request();
  }

  function setFramesVisible(visible) {
    for (const object of frameAxes) object.visible = visible;
    if (ui) ui.frames(visible);
    request();
  }

  // -- the controls -------------------------------------------------------------------------
  function buildControls() {
    const bar = document.createElement("div");
    bar.className = "kn-viewer-bar";
    // the view's own buttons sit in its top right corner, off the bar: with them the bar
    // took two rows in a 3-D pane 333 px wide (a 1400x900 studio)
    const tools = document.createElement("div");
    tools.className = "kn-viewer-tools";
    const button = (label, title, onClick, into = bar) => {
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = label;
      b.title = title;
      b.addEventListener("click", onClick);
      into.appendChild(b);
      return b;
    };
    const playButton = button("\u25B6", "Play (space)", () => (state.playing ? pause() : play()));
    playButton.className = "kn-play";
    const slider = document.createElement("input");
    slider.type = "range";
    slider.min = String(data.t[0]);
    slider.max = String(data.t[data.t.length - 1]);
    slider.step = "any";
    slider.title = "Time";
    slider.addEventListener("input", () => setTime(Number(slider.value), true));
    bar.appendChild(slider);
    const label = document.createElement("span");
    label.className = "kn-time";
    bar.appendChild(label);
    const speed = document.createElement("select");
    speed.title = "Speed";
    for (const s of SPEEDS) {
      const option = document.createElement("option");
      option.value = String(s);
      option.textContent = `${s}\u00D7`;
      speed.appendChild(option);
    }
    speed.addEventListener("change", () => setSpeed(Number(speed.value)));
    bar.appendChild(speed);
    const framesButton = button("frames", "Show or hide the axes of every frame",
                                () => setFramesVisible(!framesButton.classList.contains("kn-on")), tools);
    button("view", "Back to the first view", () => fitView(), tools);
    const title = document.createElement("div");
    title.className = "kn-viewer-title";
    title.textContent = animation.name || "";
    // elided beside the buttons in a narrow pane: the whole name on hover
    title.title = animation.name || "";
    root.append(title, tools, bar);
    const end = data.t[data.t.length - 1];
    const digits = end - data.t[0] >= 100 ? 1 : 2;
    return {
      height: () => bar.offsetHeight,
      show(time) {
        slider.value = String(time);
        label.textContent = `t = ${time.toFixed(digits)} / ${end.toFixed(digits)} s`;
      },
      playing(on) {
        playButton.textContent = on ? "\u275A\u275A" : "\u25B6";
        playButton.title = on ? "Pause (space)" : "Play (space)";
      },
      speed(s) {
        if (SPEEDS.includes(s)) speed.value = String(s);
      },
      frames(on) { framesButton.classList.toggle("kn-on", on); },
    };
  }

  function dispose() {
    state.disposed = true;
    state.playing = false;
    if (state.frame) cancelAnimationFrame(state.frame);
    resize.disconnect();
    root.removeEventListener("keydown", onKey);
    controls.dispose();
    scene.traverse(object => {
      if (object.geometry) object.geometry.dispose();
      if (object.material) object.material.dispose();
    });
    renderer.dispose();
    root.remove();
  }

  if (ui) { ui.speed(state.speed); ui.show(state.time); }
  return {
    setTime: time => setTime(time), play, pause, setSpeed, dispose,
    getTime: () => state.time, isPlaying: () => state.playing,
    renderInfo: () => ({ calls: renderer.info.render.calls, triangles: renderer.info.render.triangles,
                         gpu, antialias: renderer.getContextAttributes().antialias,
                         pixelRatio: renderer.getPixelRatio() }),
    centers: kind => (batches[kind] ? batches[kind].centers() : []),
  };
}

// The pixel ratio while playing, from the time between frames: lowered one step (to three
// quarters of the screen's, no lower) while frames come slower than SLOW, kept lower only where
// that made them faster (a renderer held back by its vertices, not its pixels, keeps its
// picture), raised again once they come faster than FAST for a while. Not two steps: a
// 32-link chain at load 8 went to 0.56, a picture that looks poor, where the pixels were ~1 ms
// of a 7 ms frame (SwiftShader, ratio 1 against 0.5) and the machine's load, not the picture,
// made frames slow (the time between frames cannot tell the two apart).
const SLOW = 1000 / 45, FAST = 1000 / 57, STEP = 0.75, SETTLE = 30, RISE = 120;

export class PixelBudget {
  constructor(base) {
    this.base = base;
    this.ratio = base;
    this.floor = base * STEP;
    this.cap = base;
    this.rose = false;
    this.trial = null;
    this.restart();
  }

  restart() {
    this.last = null;
    this.mean = null;
    this.count = 0;
  }

  /** One frame drawn at ``now`` (ms); true when the ratio changed. */
  frame(now) {
    if (this.last !== null) {
      const dt = now - this.last;
      this.mean = this.mean === null ? dt : 0.9 * this.mean + 0.1 * dt;
      this.count++;
    }
    this.last = now;
    if (this.count < SETTLE) return false;
    if (this.trial) {
      const { before, ratio } = this.trial;
      this.trial = null;
      this.count = 0;
      if (this.mean < 0.9 * before) return false;
      // no faster with fewer pixels: back, and no lower than that again
      this.floor = ratio;
      this.ratio = ratio;
      return true;
    }
    if (this.mean > SLOW && this.ratio * STEP >= this.floor - 1e-9) {
      // slow again at a ratio it rose to: it stays below that one (no see-saw)
      if (this.rose) this.cap = this.ratio * STEP;
      this.rose = false;
      this.trial = { before: this.mean, ratio: this.ratio };
      this.ratio *= STEP;
      this.count = 0;
      return true;
    }
    if (this.mean < FAST && this.ratio < this.cap - 1e-9 && this.count >= RISE) {
      this.ratio = Math.min(this.cap, this.ratio / STEP);
      this.rose = true;
      this.count = 0;
      return true;
    }
    return false;
  }
}

// A viewer with nothing to draw on: time still moves, so a host's cursor still follows.
function stub(root, data, state) {
  return {
    renderInfo: () => ({ calls: 0, triangles: 0 }), centers: () => [],
    setTime(time) { state.time = Math.min(Math.max(time, data.t[0]), data.t[data.t.length - 1]); },
    play() { state.playing = true; }, pause() { state.playing = false; }, setSpeed() {},
    dispose() { root.remove(); }, getTime: () => state.time, isPlaying: () => state.playing,
  };
}

// The poses as flat typed arrays: [x, y, z] and [w, x, y, z] per sample.
function prepare(animation) {
  const valid = animation && Array.isArray(animation.t) && animation.t.length > 0
    && Array.isArray(animation.frames);
  if (!valid)
    throw new Error("kinetwork viewer: not an animation (kinetwork.animation_data)");
  return {
    t: Float64Array.from(animation.t),
    scale: animation.scale || 1,
    frames: animation.frames.map(f => ({
      position: Float64Array.from(f.position.flat()),
      quaternion: Float64Array.from(f.quaternion.flat()),
      rows: f.position.length,
    })),
  };
}

const qa = new Quaternion(), qb = new Quaternion();

function pose(frame, i, w, object) {
  const p = frame.position, q = frame.quaternion;
  if (frame.rows === 1) {
    object.position.set(p[0], p[1], p[2]);
    object.quaternion.set(q[1], q[2], q[3], q[0]);
    return;
  }
  const j = Math.min(i + 1, frame.rows - 1), a = 3 * i, b = 3 * j;
  object.position.set(p[a] + w * (p[b] - p[a]), p[a + 1] + w * (p[b + 1] - p[a + 1]),
                      p[a + 2] + w * (p[b + 2] - p[a + 2]));
  qa.set(q[4 * i + 1], q[4 * i + 2], q[4 * i + 3], q[4 * i]);
  qb.set(q[4 * j + 1], q[4 * j + 2], q[4 * j + 3], q[4 * j]);
  object.quaternion.slerpQuaternions(qa, qb, w);
}

const direction = new Vector3();
const drawing = new Vector2();

// A shape between two frame origins: its mesh is one unit long along y, from its origin.
function stretch(object, a, b) {
  direction.subVectors(b, a);
  const length = direction.length();
  object.visible = length > 1e-12;
  if (!object.visible) return;
  object.position.copy(a);
  object.quaternion.setFromUnitVectors(Y, direction.divideScalar(length));
  object.scale.set(1, length / (object.userData.length || 1), 1);
}

function material(color) {
  return new MeshStandardMaterial({ color: new Color(color), roughness: 0.55, metalness: 0.1 });
}

// The three.js object of a shape drawn on its own (the batches take the rest): a spring
// between two frames (a unit along y that `stretch` places), a mesh file, the ground's grid.
function build(shape) {
  const kind = shape.kind;
  if (kind === "spring") {
    const turns = shape.windings || 8, radius = shape.diameter / 2;
    const helix = new Curve();
    helix.getPoint = (s, target = new Vector3()) => {
      const r = s > 0.04 && s < 0.96 ? radius : 0;
      const a = 2 * Math.PI * turns * s;
      return target.set(r * Math.cos(a), s, r * Math.sin(a));
    };
    const geometry = new TubeGeometry(helix, turns * 24, shape.wire / 2, 8, false);
    const mesh = new Mesh(geometry, material(shape.color));
    mesh.userData.length = 1;
    return mesh;
  }
  if (kind === "mesh") {
    // a mesh file's triangles, already placed and scaled in the frame's coordinates
    const geometry = new BufferGeometry();
    geometry.setAttribute("position", new Float32BufferAttribute(shape.vertices, 3));
    geometry.setIndex(shape.faces);
    geometry.computeVertexNormals();
    return new Mesh(geometry, material(shape.color));
  }
  if (kind === "grid") {
    const color = new Color(shape.color);
    const grid = new GridHelper(shape.size, shape.divisions, color.clone().multiplyScalar(0.8), color);
    grid.quaternion.setFromUnitVectors(Y, new Vector3().fromArray(shape.normal));
    grid.position.fromArray(shape.r_shape);
    return grid;
  }
  return null;
}

function injectStyle() {
  if (document.getElementById("kn-viewer-style")) return;
  const style = document.createElement("style");
  style.id = "kn-viewer-style";
  style.textContent = `
.kn-viewer{position:relative;width:100%;height:100%;overflow:hidden;outline:none;
  font:13px system-ui,-apple-system,"Segoe UI",sans-serif;color:#333;background:#f4f5f7}
.kn-viewer canvas{display:block}
.kn-viewer-title{position:absolute;top:8px;left:12px;max-width:calc(100% - 140px);overflow:hidden;
  text-overflow:ellipsis;white-space:nowrap;font-weight:600;color:#555}
.kn-viewer-tools{position:absolute;top:6px;right:8px;display:flex;gap:4px}
.kn-viewer-note{padding:2em;color:#a33}
.kn-viewer-bar{position:absolute;left:0;right:0;bottom:0;contain:layout paint;will-change:transform;display:flex;flex-wrap:wrap;align-items:center;
  gap:4px 8px;padding:6px 10px;background:#fff;border-top:1px solid #dde0e4}
.kn-viewer-bar button,.kn-viewer-tools button{font:inherit;padding:2px 8px;border:1px solid #c8ccd2;border-radius:4px;
  background:#fff;cursor:pointer;min-width:2.2em}
.kn-viewer-bar button.kn-play{width:2.8em}
.kn-viewer-bar button:hover,.kn-viewer-tools button:hover{background:#eef1f5}
.kn-viewer-tools button.kn-on{background:#dbe8fb;border-color:#8fb3e6}
.kn-viewer-bar input[type=range]{flex:1 1 60px;min-width:60px}
.kn-viewer-bar select{font:inherit}
.kn-time{font-variant-numeric:tabular-nums;white-space:nowrap}`;
  document.head.appendChild(style);
}
