// "Make subsystem": the model made of the new definition, expanded again by a flattener
// written here (its own derivation), wires the same ports together as the model it came from,
// keeps every component and parameter, and places the instance where the selection was.
import { describe, expect, it } from "vitest";
import { makeSubsystem } from "../src/studio/subsystem.js";
import seed from "../../models/double_pendulum.json" with { type: "json" };

/** Port-level connection sets (Modelica's connect semantics) of a flat body. */
function sets(connections) {
  const parent = new Map();
  const find = (x) => {
    if (!parent.has(x)) parent.set(x, x);
    while (parent.get(x) !== x) x = parent.get(x);
    return x;
  };
  for (const [a, b] of connections) parent.set(find(a), find(b));
  const groups = new Map();
  for (const x of parent.keys()) {
    const r = find(x);
    if (!groups.has(r)) groups.set(r, []);
    groups.get(r).push(x);
  }
  return new Set([...groups.values()].map((g) => g.sort().join(" ")));
}

/** The body with instance ``inst`` of ``definition`` expanded in place (names kept as inside). */
function flatten(body, inst, definition) {
  const via = (ref) => {
    const [c, p] = ref.split(".");
    return c === inst ? definition.ports[p] : ref;
  };
  return {
    components: [...body.components.filter((c) => c.name !== inst), ...definition.components],
    connections: [...body.connections.map(([a, b]) => [via(a), via(b)]), ...definition.connections],
  };
}

const positions = Object.fromEntries(Object.entries(seed.layout).map(([k, v]) => [k, { x: v.x, y: v.y }]));

describe("makeSubsystem", () => {
  for (const chosen of [["link1", "elbow", "mass2"], ["elbow", "mass2", "probe2"], ["spring"], ["shoulder", "spring", "probe1", "mass1"]]) {
    it(`wires the same ports together, made of ${chosen.join(", ")}`, () => {
      const { body, definition } = makeSubsystem(seed, chosen, "Part", "part1", positions);
      expect(body.components.map((c) => c.name)).toContain("part1");
      expect(definition.components.map((c) => c.name).sort()).toEqual([...chosen].sort());
      const flat = flatten(body, "part1", definition);
      expect(flat.components.map((c) => c.name).sort()).toEqual(seed.components.map((c) => c.name).sort());
      expect(sets(flat.connections)).toEqual(sets(seed.connections));
      // every port exposed is wired outside, and only the selection's ports are
      for (const ref of Object.values(definition.ports)) expect(chosen).toContain(ref.split(".")[0]);
    });
  }

  it("feeds the parameters the selection uses from the model's", () => {
    const { body, definition } = makeSubsystem(seed, ["link1", "elbow", "mass2"], "Forearm", "forearm1", positions);
    expect(Object.keys(definition.parameters).sort()).toEqual(["L1", "L2", "m2"]);
    expect(body.components.find((c) => c.name === "forearm1").params).toEqual({ L1: "L1", L2: "L2", m2: "m2" });
    expect(body.parameters).toEqual(seed.parameters);
  });

  it("puts the instance at the selection's centre and the definition's layout at the origin", () => {
    const chosen = ["link1", "elbow"];
    const { body, definition } = makeSubsystem(seed, chosen, "P", "p1", positions);
    const cx = (positions.link1.x + positions.elbow.x) / 2;
    expect(body.layout.p1.x).toBe(Math.round(cx / 10) * 10);
    expect(Math.min(...Object.values(definition.layout).map((p) => p.x))).toBe(0);
    expect(body.layout.link1).toBeUndefined();
  });

  it("keeps the scope's exposed ports going through the instance", () => {
    const scope = { ...seed, ports: { tip: "mass2.frame_a" } };
    const { body, definition } = makeSubsystem(scope, ["elbow", "mass2"], "P", "p1", positions);
    const [name, ref] = Object.entries(body.ports)[0];
    expect(name).toBe("tip");
    expect(definition.ports[ref.split(".")[1]]).toBe("mass2.frame_a");
  });
});
