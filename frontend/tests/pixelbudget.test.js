// The 3-D view's pixel ratio follows the time between frames: lowered while frames are slow
// and only kept where that helped, raised again when they are fast, never below half.
import { describe, expect, it } from "vitest";
import { PixelBudget, segments } from "../src/viewer3d/index.js";

/** Frames drawn ``n`` times, each taking ``cost(ratio)`` ms. */
function play(budget, n, cost) {
  let t = budget.clock || 0;
  for (let i = 0; i < n; i++) {
    t += cost(budget.ratio);
    budget.frame(t);
  }
  budget.clock = t;
}

describe("PixelBudget", () => {
  it("lowers the ratio of a renderer held back by its pixels, one step at most", () => {
    const b = new PixelBudget(1);
    play(b, 400, (r) => 10 + 40 * r * r); // 50 ms at full size
    expect(b.ratio).toBeCloseTo(0.75, 6);
    play(b, 1000, (r) => 10 + 40 * r * r); // still slow: no lower (0.56 looks poor)
    expect(b.ratio).toBeCloseTo(0.75, 6);
  });

  it("keeps the picture where fewer pixels are no faster", () => {
    const b = new PixelBudget(1);
    play(b, 400, () => 60);
    expect(b.ratio).toBe(1);
  });

  it("rises again when frames come fast, without see-sawing", () => {
    const b = new PixelBudget(1);
    play(b, 200, (r) => 40 * r * r);
    const low = b.ratio;
    expect(low).toBeLessThan(1);
    play(b, 400, () => 5); // the load went away
    expect(b.ratio).toBe(1);
    play(b, 400, (r) => 30 * r * r);
    const settled = b.ratio;
    play(b, 1000, (r) => 30 * r * r);
    expect(b.ratio).toBe(settled);
  });
});

describe("segments", () => {
  const tube = (n) => 4 * n;
  it("as many as the size on screen needs: the polygon within a third of a pixel of the circle", () => {
    for (const r of [2, 5, 10, 40, 150]) {
      const n = segments(1, tube, 6, 48, r);
      expect(r * (1 - Math.cos(Math.PI / n))).toBeLessThanOrEqual(0.35 + 1e-9);
      // and not twice what is needed
      const fewer = Math.ceil(n / 2);
      if (fewer >= 6) expect(r * (1 - Math.cos(Math.PI / fewer))).toBeGreaterThan(0.35 / 8);
    }
    expect(segments(1, tube, 6, 48, 1)).toBe(6);
    expect(segments(1, tube, 6, 48, 5000)).toBe(48);
  });
  it("fewer for many shapes: within the budget, never under the least", () => {
    expect(segments(1, tube, 12, 32)).toBe(32);
    expect(segments(32, tube, 12, 32)).toBe(32);
    expect(200 * tube(segments(200, tube, 6, 32))).toBeLessThanOrEqual(8000);
    expect(segments(5000, tube, 6, 32)).toBe(6);
  });
});
