// What the analysis panel reads of what a user typed and of the model: the values of a
// sweep's grid, and where a model can be driven (linearize's inputs).
import { portDomain, typeInfo } from "./model.js";

/**
 * The values a grid field names: "1, 2, 5", or "1 .. 3 / 5" (five values from 1 to 3).
 * @returns {{values: number[] | null, error: string | null}}
 */
export function gridValues(text) {
  const s = String(text || "").trim();
  const range = /^(\S+)\s*\.\.\s*(\S+)\s*\/\s*(\d+)$/.exec(s);
  if (range) {
    const [a, b, n] = [Number(range[1]), Number(range[2]), Number(range[3])];
    if (!Number.isFinite(a) || !Number.isFinite(b) || n < 1) return { values: null, error: `${s}: "from .. to / count", numbers` };
    return { values: n === 1 ? [a] : Array.from({ length: n }, (_, i) => a + ((b - a) * i) / (n - 1)), error: null };
  }
  const parts = s.split(/[,\s]+/).filter(Boolean);
  const values = parts.map(Number);
  if (!parts.length || values.some((v) => !Number.isFinite(v))) return { values: null, error: `${s || "(empty)"}: numbers separated by commas, or "from .. to / count"` };
  return { values, error: null };
}

/** Where a model can be driven, for linearize's inputs: Input blocks and unwired signal inputs. */
export function inputCandidates(doc, ctx) {
  const wired = new Set((doc.connections || []).flat());
  const out = [];
  for (const c of doc.components || []) {
    if (c.type === "signals.Input") out.push(c.name);
    const info = typeInfo(c.type, ctx);
    if (!info || info.subsystem) continue;
    for (const p of info.ports) {
      const path = `${c.name}.${p.name}`;
      if (p.domain === "signal_in" && !wired.has(path) && portDomain(doc, path, ctx)) out.push(path);
    }
  }
  return out;
}
