// Docstrings' literals are shown as code, never with their backticks.
import { describe, expect, it } from "vitest";
import { docParts, plainDoc } from "../src/studio/doctext.js";

describe("docParts", () => {
  it("cuts the RST literals out as code", () => {
    expect(docParts("frame_b is frame_a moved by ``r`` (resolved in frame_a).")).toEqual([
      { text: "frame_b is frame_a moved by ", code: false },
      { text: "r", code: true },
      { text: " (resolved in frame_a).", code: false },
    ]);
  });

  it("takes single backticks and roles, and leaves text without marks whole", () => {
    expect(docParts(":math:`x^2` and `y`")).toEqual([
      { text: "x^2", code: true }, { text: " and ", code: false }, { text: "y", code: true },
    ]);
    expect(docParts("a spring")).toEqual([{ text: "a spring", code: false }]);
    expect(docParts("")).toEqual([]);
    expect(docParts(undefined)).toEqual([]);
  });

  it("gives plain text for a tooltip", () => {
    expect(plainDoc("stays ``length`` apart, ``a`` b")).toBe("stays length apart, a b");
    expect(plainDoc("an odd `` mark")).toBe("an odd `` mark");
  });
});
