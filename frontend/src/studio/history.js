// Undo history of the document: the past, the present model and the future (after undo).
// Pure functions over {past, present, future, merge}: the store keeps one such object.

/** How many edits undo can go back. */
export const LIMIT = 200;
/** Edits with the same merge key this close together are one undo step (arrow-key moves). */
export const MERGE_MS = 1200;

/**
 * @typedef {{past: any[], present: any, future: any[], merge: {key: string, at: number} | null}} History
 */

/** @returns {History} a history holding only ``doc`` */
export function initHistory(doc) {
  return { past: [], present: doc, future: [], merge: null };
}

function same(a, b) {
  return a === b || JSON.stringify(a) === JSON.stringify(b);
}

/**
 * ``next`` as the present, the old present pushed on the past; an edit that changes nothing
 * is no step. With ``merge`` (a key such as "nudge:mass1"), an edit following one of the same
 * key within MERGE_MS replaces it instead of adding a step.
 * @param {History} h
 * @param {any} next
 * @param {string | null} [merge]
 * @param {number} [now]
 * @returns {History}
 */
export function pushEdit(h, next, merge = null, now = Date.now()) {
  if (!next || same(next, h.present)) return h;
  const mark = merge ? { key: merge, at: now } : null;
  if (merge && h.merge && h.merge.key === merge && now - h.merge.at < MERGE_MS && h.past.length) {
    return { past: h.past, present: next, future: [], merge: mark };
  }
  return { past: [...h.past.slice(-(LIMIT - 1)), h.present], present: next, future: [], merge: mark };
}

/** @param {History} h @returns {History} */
export function undo(h) {
  if (!h.past.length) return h;
  return { past: h.past.slice(0, -1), present: h.past[h.past.length - 1], future: [h.present, ...h.future], merge: null };
}

/** @param {History} h @returns {History} */
export function redo(h) {
  if (!h.future.length) return h;
  return { past: [...h.past, h.present], present: h.future[0], future: h.future.slice(1), merge: null };
}

/** The present replaced without a step (the same model as the server wrote it). */
export function replacePresent(h, doc) {
  return { ...h, present: doc, merge: null };
}
