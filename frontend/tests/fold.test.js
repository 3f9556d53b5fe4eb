// Folding a repeated pattern: the units found in a chain, its wiring carried by the new
// definition's ports, differing values made parameters, and no fold where the units differ.
import { describe, expect, it } from "vitest";
import { findRepeat, foldRepeat } from "../src/studio/fold.js";

/** A chain of ``n`` links (joint, body, translation) hanging from a ground, as scenes/chains.py. */
function chain(n) {
  const components = [{ name: "ground", type: "multibody.Ground", params: {} }];
  const connections = [];
  let prev = "ground.frame";
  for (let k = 0; k < n; k++) {
    components.push(
      { name: `j${k}`, type: "multibody.Revolute", params: { axis: [0, 0, 1], q0: k === 0 ? 0.5 : 0 } },
      { name: `b${k}`, type: "multibody.RigidBody", params: { mass: 1, r_cm: [0, -0.5 - k, 0] } },
      { name: `l${k}`, type: "multibody.FixedTranslation", params: { r: [0, -1, 0] } },
    );
    connections.push([prev, `j${k}.frame_a`], [`j${k}.frame_b`, `b${k}.frame_a`], [`j${k}.frame_b`, `l${k}.frame_a`]);
    prev = `l${k}.frame_b`;
  }
  return { components, connections, layout: { j3: { x: 10, y: 20 }, ground: { x: 0, y: 0 } }, ports: { tip: prev } };
}

describe("fold", () => {
  it("folds a chain's links into instances of one definition", () => {
    const doc = chain(32);
    const found = findRepeat(doc);
    expect([found.s, found.p, found.n]).toEqual([1, 3, 32]);
    const { body, definition, instances } = foldRepeat(doc, found, "Link");
    expect(instances[0]).toBe("link0");
    expect(body.components.map((c) => c.type)).toEqual(["multibody.Ground", ...Array(32).fill("Link")]);
    expect(definition.components.map((c) => c.name)).toEqual(["j", "b", "l"]);
    expect(definition.ports).toEqual({ frame_a: "j.frame_a", frame_b: "l.frame_b" });
    expect(definition.connections).toEqual([["j.frame_b", "b.frame_a"], ["j.frame_b", "l.frame_a"]]);
    expect(body.connections[0]).toEqual(["ground.frame", "link0.frame_a"]);
    expect(body.connections[5]).toEqual(["link4.frame_b", "link5.frame_a"]);
    expect(body.connections).toHaveLength(32);
    expect(body.ports).toEqual({ tip: "link31.frame_b" });
    expect(body.layout).toEqual({ ground: { x: 0, y: 0 } });
    // the joint's first angle and the body's centre of mass differ: parameters, per element
    expect(definition.parameters).toEqual({ j_q0: 0.5, b_r_cm_2: -0.5 });
    expect(definition.components[1].params.r_cm).toEqual([0, "b_r_cm_2", 0]);
    expect(body.components[3].params).toEqual({ j_q0: 0, b_r_cm_2: -2.5 });
  });

  it("finds nothing where no three units are alike", () => {
    const doc = chain(4);
    doc.connections = doc.connections.map((c) => (c[1] === "b2.frame_a" ? ["l2.frame_b", "b2.frame_a"] : c));
    const found = findRepeat(doc);
    expect(found === null || found.n < 4).toBe(true);
    expect(findRepeat(chain(2))).toBe(null);
    const skip = chain(5);
    // a wire from the first link to the fourth: not one chain of five (the first stays out)
    skip.connections.push(["j0.frame_b", "j3.frame_b"]);
    const some = findRepeat(skip);
    expect(some.n).toBe(4);
    const { body } = foldRepeat(skip, some, "Link");
    // the skipping wire goes on, from j0 to the port its unit gives j3's frame_b
    const skipping = body.connections.filter(([a, b]) => a === "j0.frame_b" && /^link\d\.\w+$/.test(b));
    expect(skipping.map(([, b]) => body.components.find((c) => c.name === b.split(".")[0]).type)).toContain("Link");
  });
});
