// What the analysis panel and the JSON view read of what a user typed.
import { describe, expect, it } from "vitest";
import { gridValues, inputCandidates } from "../src/studio/analysis.js";
import { parseJson } from "../src/studio/values.js";

describe("a sweep's grid as typed", () => {
  it("reads lists and ranges", () => {
    expect(gridValues("1, 2, 5").values).toEqual([1, 2, 5]);
    expect(gridValues("1 2 5").values).toEqual([1, 2, 5]);
    expect(gridValues("0.2 .. 1 / 5").values).toEqual([0.2, 0.4, 0.6000000000000001, 0.8, 1]);
    expect(gridValues("3 .. 3 / 1").values).toEqual([3]);
  });
  it("says what is wrong", () => {
    expect(gridValues("").error).toMatch("numbers");
    expect(gridValues("1, x").error).toMatch("numbers");
    expect(gridValues("a .. 2 / 3").error).toMatch("from .. to / count");
  });
});

describe("linearize's inputs", () => {
  const palette = {
    types: {
      "rotational.Torque": { type: "rotational.Torque", ports: [{ name: "flange", domain: "rotational" }, { name: "u", domain: "signal_in" }], params: [] },
      "signals.Input": { type: "signals.Input", ports: [{ name: "y", domain: "signal_out" }], params: [] },
      "signals.Gain": { type: "signals.Gain", ports: [{ name: "u", domain: "signal_in" }, { name: "y", domain: "signal_out" }], params: [] },
    },
  };
  it("lists Input blocks and the signal inputs left unwired", () => {
    const doc = {
      components: [
        { name: "motor", type: "rotational.Torque" },
        { name: "cmd", type: "signals.Input" },
        { name: "gain", type: "signals.Gain" },
      ],
      connections: [["cmd.y", "gain.u"]],
    };
    expect(inputCandidates(doc, { palette, doc, docPath: null, defCache: {} })).toEqual(["motor.u", "cmd"]);
  });
});

describe("the JSON view's parse", () => {
  it("gives the line and column of an error", () => {
    const { value, error } = parseJson('{\n  "a": 1,,\n}');
    expect(value).toBeNull();
    expect(error).toMatch(/^line 2, column \d+/);
    expect(parseJson('{"a": [1, 2]}')).toEqual({ value: { a: [1, 2] }, error: null });
  });
});
