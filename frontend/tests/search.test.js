// Palette search over the real palette's names and docs (palette.json: a snapshot of
// GET /api/palette, `python -c "import json; from kinetwork.studio.checks import palette;
// print(json.dumps(palette(), indent=1))" > tests/palette.json` refreshes it):
// the words people use find the types they mean, names rank above synonyms above docs.
import { describe, expect, it } from "vitest";
import { search } from "../src/studio/search.js";
import palette from "./palette.json" with { type: "json" };

const types = palette.libraries.flatMap((l) => l.types);
const found = (q) => search(types, q).map((t) => t.type);

describe("palette search", () => {
  it("finds Revolute for hinge and pin", () => {
    expect(found("hinge")[0]).toBe("multibody.Revolute");
    expect(found("pin")[0]).toBe("multibody.Revolute");
  });

  it("finds the links for link", () => {
    expect(found("link").slice(0, 2)).toEqual(["multibody.FixedTranslation", "multibody.BodyShape"]);
  });

  it("finds a pendulum's parts for pendulum", () => {
    expect(found("pendulum").slice(0, 3)).toEqual(["multibody.Revolute", "multibody.BodyShape", "multibody.RigidBody"]);
  });

  it("ranks the bodies first for body, and does not list every multibody type", () => {
    const got = found("body");
    const bodies = ["multibody.RigidBody", "multibody.BodyShape", "multibody.BodyBox", "multibody.BodyCylinder", "multibody.BodySphere"];
    expect(new Set(got.slice(0, bodies.length))).toEqual(new Set(bodies));
    expect(got.filter((t) => t.startsWith("multibody.")).length).toBeLessThan(types.filter((t) => t.type.startsWith("multibody.")).length);
  });

  it("finds springs, motors and sensors by what they do", () => {
    expect(new Set(found("spring").slice(0, 3))).toEqual(new Set(["rotational.Spring", "translational.Spring", "multibody.Spring"]));
    expect(found("springs").slice(0, 3)).toEqual(found("spring").slice(0, 3));
    expect(found("motor")[0]).toBe("electrical.DCMotor");
    expect(found("spring damper").slice(0, 3).every((t) => t.endsWith("SpringDamper"))).toBe(true);
    expect(found("angle sensor")[0]).toBe("rotational.AngleSensor");
  });

  it("needs every word to match, and nothing matches nonsense", () => {
    expect(found("zzzz")).toEqual([]);
    expect(found("spring zzzz")).toEqual([]);
    expect(found("")).toEqual([]);
  });
});
