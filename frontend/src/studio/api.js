// The studio's HTTP client: every call carries the session token (X-Kinetwork-Token), read
// once from the page's URL (?token=...). See kinetwork/studio/API.md for the contract.

const params = new URLSearchParams(window.location.search);
export const TOKEN = params.get("token") || "";
export const OPEN = params.get("open");
export const EXAMPLE = params.get("example");

export class ApiError extends Error {
  constructor(message, status, body) {
    super(message);
    this.status = status;
    this.problems = (body && body.problems) || [];
    this.body = body;
  }
}

async function call(method, path, body) {
  const init = { method, headers: { "X-Kinetwork-Token": TOKEN } };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  let res;
  try {
    res = await fetch(path, init);
  } catch (err) {
    throw new ApiError(`the studio server does not answer (${err.message}): is kinetwork studio still running?`, 0, null);
  }
  const text = await res.text();
  let data;
  try {
    data = text ? JSON.parse(text) : null;
  } catch {
    data = null;
  }
  if (!res.ok) {
    const msg = (data && (data.error || data.detail)) || `${method} ${path}: HTTP ${res.status}`;
    throw new ApiError(typeof msg === "string" ? msg : JSON.stringify(msg), res.status, data);
  }
  return data;
}

const q = encodeURIComponent;

export const api = {
  palette: () => call("GET", "api/palette"),
  facts: () => call("GET", "api/facts"),
  files: () => call("GET", "api/files"),
  examples: () => call("GET", "api/examples"),
  openPath: (path) => call("GET", `api/open?path=${q(path)}`),
  openExample: (name) => call("GET", `api/open?example=${q(name)}`),
  validate: (model, path) => call("POST", "api/validate", { model, path: path || null }),
  /** ``base``: the version of the file the model was based on (null: a new file). */
  save: (path, model, text, base) => call("POST", "api/save", { path, model, text, base: base ?? null }),
  autosave: (path, model, base, session) => call("POST", "api/autosave", { path: path || null, model, base: base ?? null, session }),
  recovery: (path) => call("GET", path ? `api/recovery?path=${q(path)}` : "api/recovery"),
  discardRecovery: (path) => call("POST", "api/recovery/discard", { path: path || null }),
  run: (model, settings, path) => call("POST", "api/run", { model, settings, path: path || null }),
  /** A run's state; ``wait``: seconds to wait for its end before answering. Its results
   * come as soon as the plots' are made, the 3-D view's poses after them (``runView``). */
  runStatus: (id, wait = 0) => call("GET", `api/run/${q(id)}?wait=${wait}&animation=later`),
  /** A run's 3-D view once its results came ahead of it: {state, animation, animation_note}. */
  runView: (id, wait = 0) => call("GET", `api/run/${q(id)}/animation?wait=${wait}`),
  sweep: (model, sweep, path) => call("POST", "api/sweep", { model, sweep, path: path || null }),
  sweepStatus: (id, wait = 0) => call("GET", `api/sweep/${q(id)}?wait=${wait}`),
  /** Cancel run or sweep ``id`` (``kind`` "run" or "sweep"). */
  cancel: (kind, id) => call("POST", `api/${kind === "sweep" ? "sweep" : "run"}/${q(id)}/cancel`),
  linearize: (model, spec, path) => call("POST", "api/linearize", { model, ...spec, path: path || null }),
};
