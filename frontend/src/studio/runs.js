// Names of runs in the plots: "run 3 · c = 5" says what differs from the run before it;
// a sweep's members are named by the values they were given.
import { TESTING, trace } from "./testing.js";
import { formatValue } from "./values.js";

const MAX_DIFFERENCES = 3;

/** The parameters (model ones, and components' "name.key") whose values differ. */
export function differences(meta, before) {
  if (!meta || !before) return [];
  const out = [];
  const a = meta.parameters || {};
  const b = before.parameters || {};
  for (const k of new Set([...Object.keys(a), ...Object.keys(b)])) {
    if (JSON.stringify(a[k]) !== JSON.stringify(b[k])) out.push(`${k} = ${a[k] === undefined ? "–" : formatValue(a[k])}`);
  }
  const old = new Map((before.components || []).map((c) => [c.name, c.params || {}]));
  for (const c of meta.components || []) {
    const was = old.get(c.name);
    if (!was) continue;
    const now = c.params || {};
    for (const k of new Set([...Object.keys(now), ...Object.keys(was)])) {
      if (JSON.stringify(now[k]) !== JSON.stringify(was[k])) out.push(`${c.name}.${k} = ${now[k] === undefined ? "default" : formatValue(now[k])}`);
    }
  }
  return out;
}

/** "run 3 · c = 5", "run 4 (partial) · spring.d = 0.2", "sweep 5 · 9 members". */
export function runLabel(entry, previous) {
  const head = `${entry.kind === "sweep" ? "sweep" : "run"} ${entry.n}${entry.state === "done" ? "" : ` (${entry.state === "cancelled" ? "partial" : entry.state})`}`;
  if (entry.kind === "sweep") return `${head} · ${(entry.members || []).length} members`;
  const diff = previous && previous.kind !== "sweep" ? differences(entry.meta, previous.meta) : [];
  if (!diff.length) return head;
  const shown = diff.slice(0, MAX_DIFFERENCES).join(", ");
  return `${head} · ${shown}${diff.length > MAX_DIFFERENCES ? ` (+${diff.length - MAX_DIFFERENCES})` : ""}`;
}

/** A sweep member's name: the values it was given, "c = 2, d = 0.5". */
export function memberLabel(member) {
  return Object.entries(member.params || {})
    .map(([k, v]) => `${k} = ${typeof v === "number" ? +v.toPrecision(4) : v}`)
    .join(", ");
}

/** What the run's status line says: "compiling 0 %", "running 42 %", "cancelling…", "done". */
export function runStatus(run) {
  if (!run) return "";
  const pct = `${Math.round((run.progress || 0) * 100)} %`;
  const what = run.kind === "sweep" ? "sweep" : "";
  switch (run.state) {
    case "starting":
      return `starting ${what}`.trim() + "…";
    case "running":
      return `${run.phase && run.phase !== "integrating" ? run.phase : what ? "sweeping" : "running"} ${pct}`;
    case "cancelling":
      return "cancelling…";
    case "done":
      return TESTING && trace.timings.runSeconds ? `done in ${trace.timings.runSeconds.toFixed(2)} s` : "done";
    case "cancelled":
      return "cancelled";
    default:
      return run.state;
  }
}
