// Problems as the server sends them (API.md: message, component, port, parameter, path,
// hint, severity), placed on the scope and block they name and said in the user's words.
// Only the fields are read, never the message's text: a reworded message cannot move a marker.

/**
 * @typedef {any} Place
 * @property {string} scope        "" for the model, else the definition the problem is in
 * @property {string | null} component  the block of that scope it is shown on
 * @property {string | null} parameter
 * @property {string | null} port
 * @property {number | null} connection
 * @property {string} message      the server's whole text
 * @property {string} text         the same in the user's words: "mass1.mass: must be >= 0"
 * @property {string | null} reason what is wrong, without the place (when the server says)
 * @property {string | null} hint
 * @property {string} severity     "error" or "warning"
 * @property {boolean} [run]       reported by a run rather than by validation
 */

/** The steps of a problem's JSON path: ["definitions", "Axis", "components", 3, "params", "k"]. */
export function pathSteps(path) {
  if (Array.isArray(path)) return path;
  if (typeof path !== "string" || !path) return [];
  const steps = [];
  for (const part of path.split(".")) {
    const head = part.split("[")[0];
    if (head) steps.push(head);
    for (const m of part.matchAll(/\[(\d+)\]/g)) steps.push(Number(m[1]));
  }
  return steps;
}

/** @returns {Place} */
export function placeOf(problem) {
  const p = problem || {};
  const steps = pathSteps(p.path);
  let scope = "";
  let rest = steps;
  if (steps[0] === "definitions" && typeof steps[1] === "string") {
    scope = steps[1];
    rest = steps.slice(2);
  }
  let component = typeof p.component === "string" ? p.component : null;
  // a path in a flat model ("upper.joint"): shown on the block placed in this scope
  if (component && component.includes(".")) component = component.split(".")[0];
  const parameter = p.parameter ?? p.param ?? null;
  let connection = Number.isInteger(p.connection) ? p.connection : null;
  if (connection === null && rest[0] === "connections" && Number.isInteger(rest[1])) connection = rest[1];
  const place = {
    scope,
    component,
    parameter: typeof parameter === "string" ? parameter : null,
    port: typeof p.port === "string" ? p.port : null,
    connection,
    message: String(p.message ?? ""),
    hint: typeof p.hint === "string" ? p.hint : null,
    severity: p.severity === "warning" ? "warning" : "error",
    reason: typeof p.reason === "string" && p.reason ? p.reason : null,
  };
  return { ...place, text: userText(p, place) };
}

/** Where a problem is, as a user names it: "mass1.mass", "shoulder.axis", "connection 3". */
export function whereOf(place) {
  if (place.component) {
    const sub = place.parameter || place.port;
    return sub ? `${place.component}.${sub}` : place.component;
  }
  if (place.connection !== null) return `connection ${place.connection + 1}`;
  return place.parameter || "";
}

/**
 * The message in the user's words: the place by name, then what is wrong. The server's
 * ``reason`` (what is wrong, without the place) is used when it sends one; otherwise its
 * message is shown whole.
 */
export function userText(problem, place) {
  const reason = typeof problem.reason === "string" && problem.reason ? problem.reason : null;
  if (!reason) return String(problem.message ?? "");
  const where = whereOf(place);
  return where ? `${where}: ${reason}` : reason;
}

/** The short text a block shows of its first problem: "mass: must be >= 0". */
export function blockText(place) {
  const sub = place.parameter || place.port;
  if (!place.reason) return place.text;
  return sub ? `${sub}: ${place.reason}` : place.reason;
}
