import { describe, expect, it } from "vitest";
import { fileName, plotCsv, plotSvg } from "../src/studio/plotexport.js";

describe("plotCsv", () => {
  it("writes the time and each curve with its unit, quoting names with commas", () => {
    const csv = plotCsv([[0, 0.5], [1.25, null], [3, 4]], ["probe1 · run 2 · c = 5, d = 1", "probe2"], "rad");
    const lines = csv.trim().split("\n");
    expect(lines[0]).toBe('t [s],"probe1 · run 2 · c = 5, d = 1 [rad]",probe2 [rad]');
    expect(lines[1]).toBe("0,1.25,3");
    expect(lines[2]).toBe("0.5,,4");
  });
  it("keeps every digit of a double", () => {
    const v = 0.1 + 0.2;
    expect(Number(plotCsv([[0], [v]], ["y"], "").trim().split("\n")[1].split(",")[1])).toBe(v);
  });
});

describe("plotSvg", () => {
  const plot = {
    title: "angle <a&b>",
    unit: "rad",
    width: 400,
    height: 260,
    x: { min: 0, max: 2, ticks: [0, 1, 2], labels: ["0", "1", "2"] },
    y: { min: -1, max: 1, ticks: [-1, 0, 1], labels: ["-1", "0", "1"] },
    data: [[0, 1, 2], [-1, null, 1]],
    series: [{ label: "probe1", stroke: "#1f77b4", width: 1.6, dash: [5, 4] }],
  };
  it("draws each curve over its points, skipping gaps, within the plot's area", () => {
    const svg = plotSvg(plot);
    const d = svg.match(/<path d="([^"]*)"[^>]*clip-path/)[1];
    expect(d.split(/[ML]/).filter(Boolean)).toHaveLength(2);
    const [x0, y0] = d.slice(1).split("L")[0].split(" ").map(Number);
    const [x1, y1] = d.split("L")[1].split(" ").map(Number);
    expect(x0).toBeLessThan(x1);
    expect(y0).toBeGreaterThan(y1); // -1 is below 1
    expect(svg).toContain('stroke-dasharray="5 4"');
  });
  it("escapes the title and names every tick", () => {
    const svg = plotSvg(plot);
    expect(svg).toContain("angle &lt;a&amp;b&gt; [rad]");
    for (const l of ["-1", "0", "1", "2"]) expect(svg).toContain(`>${l}</text>`);
  });
});

describe("fileName", () => {
  it("keeps words and drops what a file system may refuse", () => {
    expect(fileName("double pendulum", "angle/rad")).toBe("double_pendulum-angle_rad");
  });
});
