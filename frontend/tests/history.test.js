// The undo history: every edit one step, nothing lost by undo then redo, a no-op no step,
// arrow-key nudges of one selection merged, a new edit dropping the redo future.
import { describe, expect, it } from "vitest";
import { LIMIT, MERGE_MS, initHistory, pushEdit, redo, replacePresent, undo } from "../src/studio/history.js";

const doc = (n) => ({ name: "m", components: Array.from({ length: n }, (_, i) => ({ name: `c${i}` })) });

describe("history", () => {
  it("undoes and redoes every edit in order", () => {
    let h = initHistory(doc(0));
    for (let n = 1; n <= 5; n++) h = pushEdit(h, doc(n));
    const seen = [h.present.components.length];
    while (h.past.length) {
      h = undo(h);
      seen.push(h.present.components.length);
    }
    expect(seen).toEqual([5, 4, 3, 2, 1, 0]);
    for (let n = 1; n <= 5; n++) {
      h = redo(h);
      expect(h.present).toEqual(doc(n));
    }
    expect(redo(h)).toBe(h);
  });

  it("takes an edit that changes nothing as no step", () => {
    const h = pushEdit(initHistory(doc(1)), doc(2));
    expect(pushEdit(h, doc(2))).toBe(h);
    expect(pushEdit(h, h.present)).toBe(h);
    expect(pushEdit(h, null)).toBe(h);
  });

  it("drops the redo future on a new edit", () => {
    let h = pushEdit(pushEdit(initHistory(doc(0)), doc(1)), doc(2));
    h = undo(h);
    expect(h.future).toHaveLength(1);
    h = pushEdit(h, doc(7));
    expect(h.future).toHaveLength(0);
    expect(undo(h).present).toEqual(doc(1));
  });

  it("merges edits of one key close in time, not others", () => {
    let h = pushEdit(initHistory(doc(0)), doc(1));
    h = pushEdit(h, doc(2), "nudge:a", 1000);
    h = pushEdit(h, doc(3), "nudge:a", 1000 + MERGE_MS / 2);
    h = pushEdit(h, doc(4), "nudge:a", 1000 + MERGE_MS);
    expect(h.past).toHaveLength(2);
    expect(undo(h).present).toEqual(doc(1));
    h = pushEdit(h, doc(5), "nudge:b", 1000 + MERGE_MS);
    expect(h.past).toHaveLength(3);
    h = pushEdit(h, doc(6), "nudge:b", 1000 + 3 * MERGE_MS);
    expect(h.past).toHaveLength(4);
  });

  it("never merges into the opened document (the first edit is always undoable)", () => {
    const h = pushEdit(initHistory(doc(0)), doc(1), "nudge:a", 0);
    expect(undo(h).present).toEqual(doc(0));
  });

  it("keeps at most LIMIT steps, the oldest going first", () => {
    let h = initHistory(doc(0));
    for (let n = 1; n <= LIMIT + 10; n++) h = pushEdit(h, doc(n));
    expect(h.past).toHaveLength(LIMIT);
    expect(h.past[0]).toEqual(doc(10));
    expect(h.present).toEqual(doc(LIMIT + 10));
  });

  it("replaces the present without a step (the saved text read back)", () => {
    const h = pushEdit(initHistory(doc(0)), doc(1));
    const saved = replacePresent(h, doc(1));
    expect(saved.past).toBe(h.past);
    expect(undo(saved).present).toEqual(doc(0));
  });
});
