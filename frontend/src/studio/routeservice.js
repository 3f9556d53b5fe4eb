// Routing off the page's thread: the diagram's wires are routed in a web worker
// (routing.worker.js) while the page keeps answering the mouse and the keyboard, and shows
// the routes it has until the new ones arrive. Requests made while the worker is busy are
// not queued: only the latest waits, so a drag never builds a backlog of stale diagrams. A
// request for the diagram last asked about is no request: a model opening re-renders its
// blocks several times (measured, selected, validated) with the same places, and each used
// to route the whole diagram again (six routings of arm_computed_torque, 1.1 s of CPU).
import { WireRouter } from "./routing.js";

/**
 * The worker's answer to one request (also what the page computes itself where no worker
 * can be started).
 * @param {WireRouter} router
 * @param {{seq: number, rects: any[], wires: any[]}} msg
 * @param {string} where "worker" or "page": which thread routed (the tests read it)
 */
export function answer(router, msg, where = "page") {
  const t0 = performance.now();
  const out = router.route(msg.rects, msg.wires);
  return { seq: msg.seq, wires: out.wires, routed: out.routed, clashes: out.clashes, ms: performance.now() - t0, where };
}

/**
 * One routing worker and its latest request.
 *
 * ``port`` is the worker (``postMessage``, ``onmessage``), or null: the page routes in its
 * own thread, at once (tests in Node, a browser without module workers).
 */
export class RouteService {
  /**
   * @param {any} port
   * @param {(result: any) => void} deliver called with each answer, in the order asked
   */
  constructor(port, deliver) {
    this.port = port;
    this.deliver = deliver;
    this.seq = 0;
    this.last = "";
    this.busy = false;
    this.waiting = null;
    this.held = false;
    this.kept = [];
    this.local = port ? null : new WireRouter();
    if (port) {
      port.onmessage = (e) => {
        this.busy = false;
        if (this.held) this.kept.push(e.data);
        else this.deliver(e.data);
        this.next();
      };
    }
  }

  /**
   * Asks for the routes of a diagram; answered now (no worker) or when the worker is done.
   * The same diagram as the last asked is not asked again (its answer is, or will be, there).
   */
  request(rects, wires) {
    const key = JSON.stringify([rects, wires]);
    if (key === this.last) return;
    this.last = key;
    this.seq += 1;
    const msg = { seq: this.seq, rects, wires };
    if (!this.port) {
      this.deliver(answer(this.local, msg));
      return;
    }
    this.waiting = msg;
    this.next();
  }

  next() {
    if (this.busy || !this.waiting) return;
    this.busy = true;
    this.port.postMessage(this.waiting);
    this.waiting = null;
  }

  /** True while routes asked for have not been delivered. */
  get pending() {
    return this.busy || this.waiting !== null || this.kept.length > 0;
  }

  /**
   * Holds answers back (``true``) or delivers those held (``false``): the end-to-end tests
   * use it to act on the page while a routing is outstanding, whatever the machine's speed.
   */
  hold(on) {
    this.held = on;
    if (!on) {
      const kept = this.kept;
      this.kept = [];
      for (const r of kept) this.deliver(r);
    }
  }

  stop() {
    if (this.port && this.port.terminate) this.port.terminate();
  }
}

/** A routing worker, or null where module workers are not available. */
export function startWorker() {
  if (typeof Worker === "undefined") return null;
  try {
    return new Worker(new URL("./routing.worker.js", import.meta.url), { type: "module" });
  } catch {
    return null;
  }
}
