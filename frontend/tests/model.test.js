// The document model: the wiring rules of kn's Model.connect and its signal check, names,
// renames that follow the wires, removal with the wires, moves, rotation, flips, paste, values as
// typed, scopes of definitions.
import { describe, expect, it } from "vitest";
import {
  addComponent,
  connectProblem,
  editInScope,
  emptyModel,
  freshName,
  moveComponents,
  nameStem,
  pasteComponents,
  placeComponents,
  removeComponents,
  renameComponent,
  resolveScope,
  rotateComponent,
  rotatedSide,
  flipComponent,
  placedSide,
  shapeProblem,
  signalSourceProblem,
} from "../src/studio/model.js";
import { formatValue, parseValue } from "../src/studio/values.js";
import seed from "../../models/double_pendulum.json" with { type: "json" };

const port = (path, domain) => ({ path, domain });

describe("connectProblem (kn's Model.connect)", () => {
  it("refuses a port to itself, different domains, and a wire twice", () => {
    expect(connectProblem(port("a.x", "frame"), port("a.x", "frame"), [])).toMatch("to itself");
    expect(connectProblem(port("s.axis", "rotational"), port("l.frame_a", "frame"), [])).toBe(
      "cannot connect s.axis (rotational) to l.frame_a (frame): ports of different domains",
    );
    expect(connectProblem(port("a.x", "frame"), port("b.y", "frame"), [["b.y", "a.x"]])).toMatch("already connected");
    expect(connectProblem(port("a.x", "frame"), port("b.y", "frame"), [])).toBeNull();
    expect(connectProblem(port("p.port", "any"), port("b.y", "frame"), [])).toBeNull();
  });

  it("refuses two signal outputs on one signal, directly or through inputs", () => {
    const domains = { "sine.y": "signal_out", "step.y": "signal_out", "gain.u": "signal_in", "pid.u_s": "signal_in" };
    const domainOf = (p) => domains[p] || null;
    const out = (a, b, wires) => connectProblem(port(a, domains[a]), port(b, domains[b]), wires, domainOf);
    expect(out("sine.y", "step.y", [])).toBe("cannot connect sine.y to step.y: both are signal outputs, and a signal has exactly one source");
    expect(out("step.y", "gain.u", [["sine.y", "gain.u"]])).toBe(
      "cannot connect step.y to gain.u: gain.u is fed by sine.y already, and a signal has exactly one source",
    );
    // an input fed through another input wired to it
    expect(signalSourceProblem("step.y", "pid.u_s", [["sine.y", "gain.u"], ["gain.u", "pid.u_s"]], domainOf)).toMatch("fed by sine.y");
    expect(out("sine.y", "gain.u", [["gain.u", "pid.u_s"]])).toBeNull();
    expect(out("gain.u", "pid.u_s", [])).toBeNull();
  });
});

describe("names", () => {
  it("gives fresh names from a type's stem", () => {
    expect(nameStem("multibody.RigidBody")).toBe("mass");
    expect(nameStem("rotational.SpringDamper")).toBe("spring");
    expect(nameStem("signals.PID")).toBe("pID");
    expect(freshName("mass", new Set(["mass1", "mass2"]))).toBe("mass3");
    expect(freshName("mass2", new Set(["mass1", "mass2"]))).toBe("mass3");
  });

  it("renames a component with its wires, layout and exposed ports", () => {
    const body = { ...seed, ports: { tip: "mass2.frame_a" } };
    const out = renameComponent(body, "mass2", "tip_mass");
    expect(out.components.map((c) => c.name)).toContain("tip_mass");
    expect(out.connections).toContainEqual(["elbow.frame_b", "tip_mass.frame_a"]);
    expect(out.connections.flat().some((r) => r.startsWith("mass2."))).toBe(false);
    expect(out.layout.tip_mass).toEqual(seed.layout.mass2);
    expect(out.ports).toEqual({ tip: "tip_mass.frame_a" });
  });

  it("removes components with every wire and exposed port they had", () => {
    const out = removeComponents({ ...seed, ports: { a: "elbow.axis", b: "shoulder.axis" } }, ["elbow"]);
    expect(out.components).toHaveLength(seed.components.length - 1);
    expect(out.connections.flat().some((r) => r.startsWith("elbow."))).toBe(false);
    expect(out.connections).toHaveLength(seed.connections.length - 3);
    expect(out.ports).toEqual({ b: "shoulder.axis" });
    expect(out.layout.elbow).toBeUndefined();
  });
});

describe("positions", () => {
  const pos = (body) => (n) => body.layout[n] || null;
  it("moves a selection by a step, keeping the rest of each layout entry", () => {
    const body = { ...seed, layout: { ...seed.layout, mass1: { ...seed.layout.mass1, rotation: 90 } } };
    const out = moveComponents(body, ["mass1", "link1"], 10, -20, pos(body));
    expect(out.layout.mass1).toEqual({ x: seed.layout.mass1.x + 10, y: seed.layout.mass1.y - 20, rotation: 90 });
    expect(out.layout.link1).toEqual({ x: seed.layout.link1.x + 10, y: seed.layout.link1.y - 20 });
    expect(out.layout.ground).toBe(seed.layout.ground);
  });

  it("places dropped blocks and is the same body when nothing moved", () => {
    expect(placeComponents(seed, { mass1: seed.layout.mass1 })).toBe(seed);
    expect(placeComponents(seed, { mass1: { x: 1, y: 2 } }).layout.mass1).toEqual({ x: 1, y: 2 });
  });

  it("turns a block a quarter at a time, back to none after four", () => {
    let body = seed;
    const sides = [];
    for (let k = 0; k < 4; k++) {
      body = rotateComponent(body, "mass1", pos(body));
      sides.push(rotatedSide("left", /** @type {any} */ (body.layout.mass1).rotation));
    }
    expect(sides).toEqual(["top", "right", "bottom", "left"]);
    expect(body.layout.mass1).toEqual(seed.layout.mass1);
  });

  it("flips a block left to right, in its own frame before it turns, and back", () => {
    const flipped = flipComponent(seed, "mass1", pos(seed));
    expect(/** @type {any} */ (flipped.layout.mass1).flip).toBe(true);
    expect(placedSide("left", 0, true)).toBe("right");
    expect(placedSide("top", 0, true)).toBe("top");
    // mirrored, then a quarter turn: its left port goes to the right, then to the bottom
    expect(placedSide("left", 90, true)).toBe("bottom");
    expect(flipComponent(flipped, "mass1", pos(flipped)).layout.mass1).toEqual(seed.layout.mass1);
  });

  it("pastes copies with fresh names and their own wires, at the place asked", () => {
    const clip = {
      components: seed.components.filter((c) => ["elbow", "mass2"].includes(c.name)),
      connections: [["elbow.frame_b", "mass2.frame_a"]],
      positions: { elbow: { x: 240, y: 0 }, mass2: { x: 320, y: 0 } },
    };
    const { body, names } = pasteComponents(seed, clip, { x: 500, y: 300 });
    expect(names).toEqual(["elbow1", "mass3"]);
    expect(body.connections.slice(-1)).toEqual([["elbow1.frame_b", "mass3.frame_a"]]);
    expect(body.layout.elbow1).toEqual({ x: 500, y: 300 });
    expect(body.layout.mass3).toEqual({ x: 580, y: 300 });
    // without a place: below the originals, not on them
    const below = pasteComponents(seed, clip, null).body.layout;
    expect(below.elbow1.y).toBeGreaterThan(clip.positions.elbow.y + 60);
  });
});

describe("values as typed", () => {
  it("reads numbers, expressions and vectors back as they print", () => {
    for (const v of [1.5, -0.25, 1e-6, 2e20, "-L1/2", [0, "-L1", 0], [[1, 0], [0, 1]], true]) {
      expect(parseValue(formatValue(v))).toEqual(v);
    }
    expect(parseValue("")).toBeUndefined();
    expect(parseValue("  3 ")).toBe(3);
    expect(parseValue("2 kg")).toBe("2 kg");
  });
});

describe("scopes", () => {
  const palette = { types: Object.fromEntries(seed.components.map((c) => [c.type, { type: c.type, ports: [], params: [] }])) };
  const arm = {
    ...emptyModel("arm"),
    version: 2,
    components: [{ name: "upper", type: "Link", params: {} }],
    definitions: { Link: { ports: { a: "j.frame_a" }, components: [{ name: "j", type: "multibody.Revolute", params: {} }], connections: [] } },
  };
  const ctx = { palette, docPath: "models/arm.json", defCache: {} };

  it("edits a definition opened, leaving the model's own body", () => {
    const out = editInScope(arm, ["Link"], ctx, (b) => addComponent(b, { name: "k", type: "multibody.Revolute", params: {} }, { x: 0, y: 0 }));
    expect(out.definitions.Link.components.map((c) => c.name)).toEqual(["j", "k"]);
    expect(out.components).toEqual(arm.components);
    expect(resolveScope(["Link"], { ...ctx, doc: out }).body.components).toHaveLength(2);
  });

  it("leaves the document alone when the scope is gone", () => {
    expect(editInScope(arm, ["Nope"], ctx, () => ({}))).toBe(arm);
  });

  it("says why a file cannot be drawn", () => {
    expect(shapeProblem(seed)).toBeNull();
    expect(shapeProblem([1])).toMatch("JSON object");
    expect(shapeProblem({ components: { a: 1 } })).toBe("components: must be a list");
    expect(shapeProblem({ connections: [["a.x"]] })).toMatch("connections[0]");
  });
});
