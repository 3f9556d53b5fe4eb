// Problems placed by their fields, never by their text, and said in the user's words.
import { describe, expect, it } from "vitest";
import { blockText, pathSteps, placeOf, whereOf } from "../src/studio/problems.js";
import { differences, memberLabel, runLabel, runStatus } from "../src/studio/runs.js";

describe("problems", () => {
  it("places a problem on its block and parameter, in the user's words", () => {
    const p = placeOf({ message: 'components[4] "mass1" params.mass = -1 kg: must be >= 0.0', component: "mass1", parameter: "mass", path: "components[4].params.mass", reason: "must be >= 0.0 (got -1 kg)", severity: "error" });
    expect([p.scope, p.component, p.parameter]).toEqual(["", "mass1", "mass"]);
    expect(p.text).toBe("mass1.mass: must be >= 0.0 (got -1 kg)");
    expect(p.text).not.toMatch("components[");
    expect(blockText(p)).toBe("mass: must be >= 0.0 (got -1 kg)");
  });

  it("reads the place from the fields, whatever the text says", () => {
    const p = placeOf({ message: "something reworded entirely", component: "elbow", port: "axis", reason: "not connected" });
    expect(whereOf(p)).toBe("elbow.axis");
    expect(p.text).toBe("elbow.axis: not connected");
  });

  it("finds the definition and the wire from the path", () => {
    expect(pathSteps("definitions.Axis.components[3].params.k")).toEqual(["definitions", "Axis", "components", 3, "params", "k"]);
    const p = placeOf({ message: "x", component: "pid", parameter: "k", path: "definitions.Axis.components[3].params.k" });
    expect([p.scope, p.component, p.parameter]).toEqual(["Axis", "pid", "k"]);
    const w = placeOf({ message: "x", path: ["connections", 2], reason: "ports of different domains" });
    expect([w.connection, w.text]).toEqual([2, "connection 3: ports of different domains"]);
  });

  it("shows a flat model's component on the block placed in the model", () => {
    expect(placeOf({ message: "x", component: "forearm1.elbow" }).component).toBe("forearm1");
  });

  it("takes the older fields (param, connection) and a bare message", () => {
    const p = placeOf({ message: "m", component: "a", param: "k", connection: null });
    expect(p.parameter).toBe("k");
    expect(placeOf({ message: "no place" })).toMatchObject({ component: null, text: "no place", severity: "error" });
  });
});

describe("run labels", () => {
  const meta = (c, springC) => ({ parameters: { c, d: 1 }, components: [{ name: "spring", params: { c: springC } }] });
  it("names what differs from the run before", () => {
    expect(differences(meta(5, "c"), meta(1, "c"))).toEqual(["c = 5"]);
    expect(differences(meta(1, 2), meta(1, "c"))).toEqual(["spring.c = 2"]);
    expect(runLabel({ n: 2, kind: "run", state: "done", meta: meta(5, "c") }, { kind: "run", meta: meta(1, "c") })).toBe("run 2 · c = 5");
    expect(runLabel({ n: 3, kind: "run", state: "cancelled", meta: meta(5, "c") }, null)).toBe("run 3 (partial)");
  });

  it("names a sweep's members by their values", () => {
    expect(memberLabel({ params: { c: 2, d: 0.123456 } })).toBe("c = 2, d = 0.1235");
    expect(runLabel({ n: 4, kind: "sweep", state: "done", members: [{}, {}, {}] })).toBe("sweep 4 · 3 members");
  });

  it("says what a run or sweep is doing, the C compile included", () => {
    expect(runStatus({ kind: "run", state: "running", phase: "compiling", progress: 0 })).toBe("compiling 0 %");
    expect(runStatus({ kind: "run", state: "running", phase: "integrating", progress: 0.42 })).toBe("running 42 %");
    expect(runStatus({ kind: "sweep", state: "running", phase: "compiling", progress: 0 })).toBe("compiling 0 %");
    expect(runStatus({ kind: "sweep", state: "running", phase: "integrating", progress: 0.5 })).toBe("sweeping 50 %");
    expect(runStatus({ kind: "run", state: "cancelling" })).toBe("cancelling…");
  });
});
