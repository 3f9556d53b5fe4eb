// Parameter values as a user types and reads them: numbers, expressions in the model's
// parameters, vectors and matrices, and the identifiers an expression mentions.
/** A parameter value as text in an input: 1.5, "-L1/2" as -L1/2, [0, "-L1", 0] as [0, -L1, 0]. */
export function formatValue(v) {
  if (v === undefined || v === null) return "";
  if (typeof v === "string") return v;
  if (Array.isArray(v)) return `[${v.map(formatValue).join(", ")}]`;
  if (typeof v === "number") return formatNumber(v);
  return JSON.stringify(v);
}

export function formatNumber(x) {
  if (!Number.isFinite(x)) return String(x);
  const a = Math.abs(x);
  // the shortest text that reads back as the same number; 1e-06 rather than 0.000001
  if (a !== 0 && (a < 1e-4 || a >= 1e15)) return x.toExponential();
  return String(x);
}

/**
 * Text typed into a parameter field -> a file value: "" -> undefined (the default), a number,
 * an expression string, or a (nested) list of those for "[a, b, c]".
 */
export function parseValue(text) {
  const s = String(text).trim();
  if (s === "") return undefined;
  if (s.startsWith("[")) {
    const items = splitList(s);
    if (items) return items.map(parseValue).map((x) => (x === undefined ? 0 : x));
  }
  if (s === "true") return true;
  if (s === "false") return false;
  if (/^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(s)) return Number(s);
  return s;
}

function splitList(s) {
  if (!s.endsWith("]")) return null;
  const inner = s.slice(1, -1);
  const items = [];
  let depth = 0;
  let cur = "";
  for (const ch of inner) {
    if (ch === "[" || ch === "(") depth++;
    if (ch === "]" || ch === ")") depth--;
    if (ch === "," && depth === 0) {
      items.push(cur);
      cur = "";
    } else cur += ch;
  }
  if (cur.trim() !== "" || items.length) items.push(cur);
  return items.map((x) => x.trim());
}

/** The identifiers an expression (or a nested value) mentions. */
export function identifiers(value, out = new Set()) {
  if (typeof value === "string") {
    for (const m of value.matchAll(/[A-Za-z_][A-Za-z0-9_]*/g)) out.add(m[0]);
  } else if (Array.isArray(value)) {
    for (const v of value) identifiers(v, out);
  }
  return out;
}


/** The JSON error of ``text`` with its line and column, or null; and the parsed value. */
export function parseJson(text) {
  try {
    return { value: JSON.parse(text), error: null };
  } catch (e) {
    const msg = String(e.message || e);
    const at = /position (\d+)/.exec(msg);
    if (!at) return { value: null, error: msg };
    const upto = text.slice(0, Number(at[1]));
    const line = upto.split("\n").length;
    const col = upto.length - upto.lastIndexOf("\n");
    return { value: null, error: `line ${line}, column ${col}: ${msg.replace(/\s*\(line \d+ column \d+\)/, "")}` };
  }
}
