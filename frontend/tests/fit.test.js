import { describe, expect, it } from "vitest";
import { diagramExtent, fitViewport, MARGIN, WIRE_PAD } from "../src/studio/fit.js";
import { blockGeometry, BLOCK_W, labelWidth } from "../src/studio/geometry.js";

const shown = (b, v) => ({ x: b.x * v.zoom + v.x, y: b.y * v.zoom + v.y, width: b.width * v.zoom, height: b.height * v.zoom });
const apart = (a, b) => a.x + a.width <= b.x || b.x + b.width <= a.x || a.y + a.height <= b.y || b.y + b.height <= a.y;

describe("fitViewport", () => {
  const pane = { width: 1000, height: 600 };
  const zoomButtons = { x: 15, y: 480, width: 32, height: 105 };
  const minimap = { x: 845, y: 495, width: 140, height: 90 };

  it("fills the pane where nothing floats over it", () => {
    const b = { x: 100, y: 50, width: 2000, height: 400 };
    const v = fitViewport(b, pane, [], 1.1, 0.1);
    const s = shown(b, v);
    expect(v.zoom).toBeCloseTo((1000 - 2 * MARGIN) / 2000, 9);
    expect(s.x).toBeCloseTo(MARGIN, 9);
    expect(s.y + s.height / 2).toBeCloseTo(300, 9);
  });

  it("keeps a wide diagram off the corners' controls: above them, or between them", () => {
    for (const b of [{ x: 0, y: 0, width: 3000, height: 1800 }, { x: -50, y: 20, width: 900, height: 1400 }, { x: 0, y: 0, width: 4000, height: 900 }]) {
      const v = fitViewport(b, pane, [zoomButtons, minimap], 1.1, 0.1);
      const s = shown(b, v);
      expect(apart(s, zoomButtons) && apart(s, minimap)).toBe(true);
      expect(s.x).toBeGreaterThanOrEqual(0);
      expect(s.y).toBeGreaterThanOrEqual(0);
      expect(s.x + s.width).toBeLessThanOrEqual(pane.width + 1e-9);
      expect(s.y + s.height).toBeLessThanOrEqual(pane.height + 1e-9);
      // and no smaller than it must be: the larger of the two rooms
      const above = Math.min((1000 - 2 * MARGIN) / b.width, (480 - 2 * MARGIN) / b.height);
      const between = Math.min((845 - 47 - 2 * MARGIN) / b.width, (600 - 2 * MARGIN) / b.height);
      expect(v.zoom).toBeCloseTo(Math.min(1.1, Math.max(above, between)), 9);
    }
  });

  it("a small diagram is not blown up beyond the most zoom", () => {
    const v = fitViewport({ x: 0, y: 0, width: 100, height: 50 }, pane, [zoomButtons, minimap], 1.1, 0.1);
    expect(v.zoom).toBe(1.1);
  });
});

describe("block widths follow their ports' names", () => {
  const port = (name, side) => ({ name, domain: "multibody", side });
  it("short names keep the usual width, long ones widen the block to hold them", () => {
    expect(blockGeometry([port("frame_a", "left"), port("frame_b", "right")]).width).toBe(BLOCK_W);
    const g = blockGeometry([port("link1_frame_a", "left"), port("shoulder_frame_b", "right")]);
    expect(g.labels.left).toBe(labelWidth("link1_frame_a"));
    expect(g.width).toBeGreaterThanOrEqual(labelWidth("link1_frame_a") + labelWidth("shoulder_frame_b") + 36);
    expect(g.width % 2).toBe(0);
    // every handle on the block's border: the wires end where the block is drawn
    for (const h of g.handles) expect([0, g.width]).toContain(h.x);
  });
  it("a name's width grows with its letters and is capped", () => {
    expect(labelWidth("frame_a")).toBeLessThan(labelWidth("frame_a_long"));
    expect(labelWidth("WWWW")).toBeGreaterThan(labelWidth("iiii"));
    expect(labelWidth("x".repeat(200))).toBe(120);
  });
});

describe("fitViewport with the blocks", () => {
  it("leaves a control over an empty corner of the diagram where no block is under it", () => {
    const pane = { width: 1000, height: 600 };
    const minimap = { x: 845, y: 495, width: 140, height: 90 };
    const bounds = { x: 0, y: 0, width: 1000, height: 600 };
    // an L: blocks along the top and down the left, the bottom right corner empty
    const blocks = [{ x: 0, y: 0, width: 1000, height: 100 }, { x: 0, y: 0, width: 100, height: 600 }];
    const v = fitViewport(bounds, pane, [minimap], 1.1, 0.1, blocks);
    expect(v.zoom).toBeCloseTo((600 - 2 * MARGIN) / 600, 9);
    // the extent alone would have to shrink to clear it
    expect(fitViewport(bounds, pane, [minimap], 1.1, 0.1).zoom).toBeLessThan(v.zoom);
  });
});

describe("diagramExtent", () => {
  it("holds the blocks, what stands out of them and every wire's path", () => {
    const blocks = { x: 0, y: 0, width: 400, height: 200 };
    // a port name left of the first block, a wire round the top of the blocks and one below
    const parts = [{ x: -30, y: 80, width: 25, height: 10 }];
    const wires = [[{ x: 100, y: 0 }, { x: 100, y: -40 }, { x: 300, y: -40 }, { x: 300, y: 0 }], [{ x: 50, y: 200 }, { x: 50, y: 260 }, { x: 450, y: 260 }]];
    const e = diagramExtent(blocks, parts, wires);
    expect(e).toEqual({ x: -30, y: -40 - WIRE_PAD, width: 450 + WIRE_PAD + 30, height: 260 + WIRE_PAD + 40 + WIRE_PAD });
    // fitted to it, the top wire is inside the pane, MARGIN from its edge
    const v = fitViewport(e, { width: 1000, height: 600 }, [], 1.1, 0.1);
    expect(-40 * v.zoom + v.y).toBeGreaterThanOrEqual(MARGIN);
    expect(diagramExtent(blocks, [], [])).toEqual(blocks);
  });
});
