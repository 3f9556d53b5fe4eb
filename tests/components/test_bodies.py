"""Bodies with shapes (MSL's Parts.BodyBox, BodyCylinder, and a sphere) and RigidBody's looks.

Mass, centre of mass and inertia are checked against independent references: the box's by
Gauss-Legendre quadrature over its volume (exact for the quadratic integrands), the
cylinder's and the sphere's against the textbook closed forms. In motion a shaped body must
be what a FixedTranslation and a RigidBody with those numbers are, and a box pendulum what
the closed-form compound pendulum is.
"""

import json
import math

import casadi as ca
import jsonschema
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import kinetwork as kn
from scenes.loops import fourbar_guesses

mb = kn.multibody
STEEL, ALUMINIUM = 7700.0, 2700.0


def numbers(expr):
    """A CasADi expression without symbols, as numpy."""
    return np.array(ca.evalf(ca.SX(expr)), dtype=float)


def properties(body):
    m, c, inertia = body.mass_properties()
    return numbers(m).item(), numbers(c).ravel(), numbers(inertia)


def basis(length_direction, width_direction):
    """Columns: the box's length, width and height axes in frame_a (Gram-Schmidt)."""
    ex = np.asarray(length_direction, float) / np.linalg.norm(length_direction)
    ey = np.asarray(width_direction, float) - np.dot(width_direction, ex) * ex
    ey /= np.linalg.norm(ey)
    return np.column_stack([ex, ey, np.cross(ex, ey)])


def box_reference(length, width, height, density, axes=np.eye(3), start=np.zeros(3),
                  inner=(0.0, 0.0)):
    """Mass, centre of mass and inertia about it (frame_a axes) of a box, hollow along its
    length when ``inner`` (width, height) is not zero, by 3-point Gauss-Legendre quadrature
    over its volume: the frame around the hole is four rectangles of cross-section."""
    wi, hi = inner
    w2, h2, wi2, hi2 = width / 2, height / 2, wi / 2, hi / 2
    sections = [((-w2, w2), (hi2, h2)), ((-w2, w2), (-h2, -hi2)),
                ((-w2, -wi2), (-hi2, hi2)), ((wi2, w2), (-hi2, hi2))]
    nodes, weights = np.polynomial.legendre.leggauss(3)
    points, masses = [], []
    for (y0, y1), (z0, z1) in sections:
        for xi, wx in zip(nodes, weights):
            for yi, wy in zip(nodes, weights):
                for zi, wz in zip(nodes, weights):
                    local = [length / 2 * (1 + xi), (y0 + y1) / 2 + (y1 - y0) / 2 * yi,
                             (z0 + z1) / 2 + (z1 - z0) / 2 * zi]
                    points.append(start + axes @ local)
                    masses.append(density * wx * wy * wz * length * (y1 - y0) * (z1 - z0) / 8)
    points, masses = np.array(points), np.array(masses)
    mass = masses.sum()
    centre = masses @ points / mass
    d = points - centre
    inertia = sum(w * (p @ p * np.eye(3) - np.outer(p, p)) for w, p in zip(masses, d))
    return mass, centre, inertia


def cylinder_reference(length, diameter, density, axis=(1.0, 0.0, 0.0), start=np.zeros(3),
                       inner_diameter=0.0):
    """A thick-walled tube, the textbook way: m = rho pi l (R^2 - Ri^2), m (R^2 + Ri^2) / 2
    about its axis, m (3 (R^2 + Ri^2) + l^2) / 12 across it."""
    R, Ri = diameter / 2, inner_diameter / 2
    mass = density * math.pi * length * (R**2 - Ri**2)
    e = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.array([0.0, 0.0, 1.0]) if abs(e[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    Q = basis(e, helper)
    principal = np.diag([mass * (R**2 + Ri**2) / 2,
                         mass * (3 * (R**2 + Ri**2) + length**2) / 12,
                         mass * (3 * (R**2 + Ri**2) + length**2) / 12])
    return mass, start + e * length / 2, Q @ principal @ Q.T


def assert_properties(body, reference):
    m, c, inertia = properties(body)
    m_ref, c_ref, i_ref = reference
    assert m == pytest.approx(m_ref, rel=1e-12)
    np.testing.assert_allclose(c, c_ref, rtol=1e-12, atol=1e-12 * np.abs(c_ref).max())
    np.testing.assert_allclose(inertia, i_ref, rtol=1e-12, atol=1e-12 * np.abs(i_ref).max())


# -- mass, centre of mass, inertia ------------------------------------------------------------

def test_solid_box_along_r():
    box = mb.BodyBox("b", r=[0.8, 0, 0], width=0.1, height=0.05, density=STEEL)
    assert_properties(box, box_reference(0.8, 0.1, 0.05, STEEL))


def test_box_defaults_follow_msl():
    """length |r - r_shape|, width length/20 (world.defaultWidthFraction), height = width;
    width_direction [0, 1, 0] parallel to the length: Frames.from_nxy takes [1, 0, 0]."""
    box = mb.BodyBox("b", r=[0, -1.2, 0])
    axes = np.column_stack([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    assert_properties(box, box_reference(1.2, 0.06, 0.06, STEEL, axes))


def test_hollow_box():
    box = mb.BodyBox("b", r=[0.5, 0, 0], width=0.08, height=0.06, inner_width=0.05,
                     inner_height=0.03, density=ALUMINIUM)
    assert_properties(box, box_reference(0.5, 0.08, 0.06, ALUMINIUM, inner=(0.05, 0.03)))
    square = mb.BodyBox("s", r=[0.5, 0, 0], width=0.08, inner_width=0.05)  # inner_height too
    assert_properties(square, box_reference(0.5, 0.08, 0.08, STEEL, inner=(0.05, 0.05)))


def test_tilted_box_with_its_own_width_direction():
    """A box that starts at r_shape and runs along a length direction of its own (not that of
    r), its width along a direction that is not orthogonal to the length: the inertia is
    resolved along the box's own axes."""
    length_direction, width_direction = [1.0, 2.0, -0.5], [0.0, 0.3, 1.0]
    start = np.array([0.1, -0.2, 0.05])
    box = mb.BodyBox("b", r=[0.3, 0.4, -0.2], r_shape=start.tolist(),
                     length_direction=length_direction, width_direction=width_direction,
                     length=0.7, width=0.12, height=0.04, inner_width=0.06,
                     inner_height=0.02, density=STEEL)
    axes = basis(length_direction, width_direction)
    assert_properties(box, box_reference(0.7, 0.12, 0.04, STEEL, axes, start, (0.06, 0.02)))


def test_tilted_box_along_r_minus_r_shape():
    r, start = np.array([0.6, 0.3, 0.2]), np.array([0.1, 0.0, -0.1])
    box = mb.BodyBox("b", r=r.tolist(), r_shape=start.tolist(), width=0.1,
                     width_direction=[0, 0, 1], density=STEEL)
    axes = basis(r - start, [0, 0, 1])
    assert_properties(box, box_reference(np.linalg.norm(r - start), 0.1, 0.1, STEEL, axes,
                                         start))


def test_solid_cylinder():
    cyl = mb.BodyCylinder("c", r=[0, 0, 0.9], diameter=0.1, density=STEEL)
    assert_properties(cyl, cylinder_reference(0.9, 0.1, STEEL, axis=[0, 0, 1]))
    default = mb.BodyCylinder("d", r=[1.0, 0, 0])            # diameter length/20
    assert_properties(default, cylinder_reference(1.0, 0.05, STEEL))


def test_hollow_tilted_cylinder():
    axis, start = [1.0, -1.0, 2.0], np.array([0.0, 0.1, 0.2])
    cyl = mb.BodyCylinder("c", r=[0.2, 0, 0], r_shape=start.tolist(), length_direction=axis,
                          length=0.4, diameter=0.08, inner_diameter=0.06, density=ALUMINIUM)
    assert_properties(cyl, cylinder_reference(0.4, 0.08, ALUMINIUM, axis, start, 0.06))


def test_sphere():
    d, rho = 0.12, STEEL
    m = rho * 4 / 3 * math.pi * (d / 2) ** 3
    assert_properties(mb.BodySphere("s", diameter=d, density=rho),
                      (m, np.zeros(3), 2 / 5 * m * (d / 2) ** 2 * np.eye(3)))


def test_mass_properties_of_symbols():
    """Parameters may be expressions in model parameters: the formulas run on SX symbols."""
    L, W = ca.SX.sym("L"), ca.SX.sym("W")
    box = mb.BodyBox("b", r=[0, "-L", 0], width="W", width_direction=[1, 0, 0],
                     height=0.03, density=STEEL)
    bound = box.bound({**box._values, "r": [ca.SX(0), -L, ca.SX(0)], "width": W,
                       "height": ca.SX(0.03), "density": ca.SX(STEEL)})
    f = ca.Function("f", [L, W], list(bound.mass_properties()))
    m, c, inertia = (np.array(v, dtype=float) for v in f(0.5, 0.05))
    axes = np.column_stack([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    m_ref, c_ref, i_ref = box_reference(0.5, 0.05, 0.03, STEEL, axes)
    assert m.item() == pytest.approx(m_ref, rel=1e-12)
    np.testing.assert_allclose(c.ravel(), c_ref, atol=1e-15)
    np.testing.assert_allclose(inertia, i_ref, rtol=1e-12, atol=1e-15)


# -- in motion --------------------------------------------------------------------------------

def box_pendulum(kind="shape"):
    """A box hanging from a revolute about z: length L (0.5) along -y, width 0.05 along x,
    height 0.03; "parts": a FixedTranslation and a RigidBody of the box's reference numbers."""
    m = kn.Model("box_pendulum", parameters={"L": 0.5, "g": 9.81})
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Revolute("pivot", axis=[0, 0, 1], q0=1.2))
    m.connect("ground.frame", "pivot.frame_a")
    if kind == "shape":
        m.add(mb.BodyBox("box", r=[0, "-L", 0], width_direction=[1, 0, 0], width=0.05,
                         height=0.03, density=ALUMINIUM))
    else:
        axes = np.column_stack([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
        mass, centre, inertia = box_reference(0.5, 0.05, 0.03, ALUMINIUM, axes)
        m.add(mb.FixedTranslation("box", r=[0, "-L", 0]))
        m.add(mb.RigidBody("box_body", mass=mass, r_cm=centre.tolist(),
                           inertia=inertia.tolist()))
        m.connect("pivot.frame_b", "box_body.frame_a")
    m.connect("pivot.frame_b", "box.frame_a")
    return m


def compound_pendulum(t, L, width, g, q0):
    """I_pivot q'' = -m g (L/2) sin q, I_pivot = m (L^2 + w^2) / 12 + m (L/2)^2 (the mass
    cancels), integrated with DOP853 at rtol 1e-12."""
    k = g * L / 2 / ((L**2 + width**2) / 12 + L**2 / 4)
    sol = solve_ivp(lambda _, x: [x[1], -k * np.sin(x[0])], (t[0], t[-1]), [q0, 0.0],
                    method="DOP853", t_eval=t, rtol=1e-12, atol=1e-14)
    return sol.y.T


def test_box_pendulum_is_the_compound_pendulum():
    model = box_pendulum()
    system = model.compile()
    assert system.state_names == ["pivot.q", "pivot.qd"]    # the box costs no state
    for L in (0.5, 0.8):                                     # a new L: no recompilation
        res = kn.simulate(system, t_end=3.0, n_points=301, rtol=1e-12, atol=1e-12,
                          params={"L": L}, jit=False)
        reference = compound_pendulum(res.t, L, 0.05, 9.81, 1.2)
        np.testing.assert_allclose(res.states, reference, rtol=0, atol=1e-8)
    assert model.compile() is system


def test_box_pendulum_is_a_fixed_translation_with_a_rigid_body():
    shape, parts = (kn.simulate(box_pendulum(kind), t_end=3.0, n_points=301, rtol=1e-12,
                                atol=1e-12, jit=False) for kind in ("shape", "parts"))
    np.testing.assert_allclose(shape.states, parts.states, rtol=0, atol=1e-10)


def _shaped(model, name, kind, **params):
    """``kind`` "shape": a body with a shape; "parts": a FixedTranslation with a RigidBody
    of the reference numbers on its frame_a. Returns the two frames."""
    if kind == "shape":
        cls = mb.BodyCylinder if "diameter" in params else mb.BodyBox
        model.add(cls(name, **params))
        return f"{name}.frame_a", f"{name}.frame_b"
    r = np.asarray(params["r"], float)
    if "diameter" in params:
        mass, centre, inertia = cylinder_reference(
            params["length"], params["diameter"], params["density"],
            params["length_direction"], np.asarray(params["r_shape"], float),
            params.get("inner_diameter", 0.0))
    else:
        axes = basis(params["length_direction"], params["width_direction"])
        mass, centre, inertia = box_reference(
            params["length"], params["width"], params["height"], params["density"], axes,
            np.asarray(params["r_shape"], float),
            (params.get("inner_width", 0.0), params.get("inner_height", 0.0)))
    model.add(mb.FixedTranslation(name, r=r.tolist()))
    model.add(mb.RigidBody(f"{name}_body", mass=mass, r_cm=centre.tolist(),
                           inertia=inertia.tolist()))
    model.connect(f"{name}.frame_a", f"{name}_body.frame_a")
    return f"{name}.frame_a", f"{name}.frame_b"


BOX = dict(r=[0.3, -0.4, 0.2], r_shape=[0.05, -0.02, 0.0], length_direction=[1.0, -1.0, 0.4],
           width_direction=[0.0, 0.2, 1.0], length=0.45, width=0.1, height=0.06,
           inner_width=0.05, inner_height=0.03, density=STEEL)
CYLINDER = dict(r=[0.0, -0.3, 0.25], r_shape=[0.0, 0.0, 0.0], length_direction=[0.0, -1.2, 1.0],
                length=0.39, diameter=0.05, inner_diameter=0.03, density=ALUMINIUM)


def spatial_scene(kind, reversed_box):
    """A box on a ball joint, a tube on a universal joint at its far end, a sphere at the
    tube's end (a RigidBody in the parts scene); the box either way round (frame_b towards the
    ground when ``reversed_box``). Probes on the frames of box and tube."""
    m = kn.Model(f"spatial_{kind}")
    m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    m.add(mb.Spherical("ball", angles0=[0.3, -0.2, 0.5], w0=[1.0, -0.5, 2.0]))
    m.connect("ground.frame", "ball.frame_a")
    a, b = _shaped(m, "box", kind, **BOX)
    near, far = (b, a) if reversed_box else (a, b)
    m.connect("ball.frame_b", near)
    m.add(mb.Universal("cardan", n_a=[0, 0, 1], n_b=[1, 0, 0], q0=[0.4, -0.3],
                       qd0=[0.5, 1.0]))
    m.connect(far, "cardan.frame_a")
    ta, tb = _shaped(m, "tube", kind, **CYLINDER)
    m.connect("cardan.frame_b", ta)
    d = 0.08
    if kind == "shape":
        m.add(mb.BodySphere("ball_end", diameter=d, density=STEEL))
    else:
        mass = STEEL * math.pi * d**3 / 6
        m.add(mb.RigidBody("ball_end", mass=mass, inertia=[mass * d**2 / 10] * 3))
    m.connect(tb, "ball_end.frame_a")
    probes = [("pa", a), ("pb", b), ("pt", ta), ("pe", tb)]
    if kind == "parts":         # what the shaped body takes at frame_a is the sum of these
        probes += [("pa_body", "box_body.frame_a"), ("pt_body", "tube_body.frame_a")]
    for name, port in probes:
        m.add(kn.Probe(name, quantities=["position", "force", "torque"]))
        m.connect(f"{name}.port", port)
    return m


@pytest.mark.parametrize("reversed_box", [False, True], ids=["box_forward", "box_reversed"])
def test_shaped_bodies_move_as_a_fixed_translation_with_a_rigid_body(reversed_box):
    """The same states and the same cut forces and torques at every frame of the shaped
    bodies as the scene built of FixedTranslations and RigidBodies of the reference numbers
    (the box passing its wrench on either way round)."""
    systems = {kind: spatial_scene(kind, reversed_box).compile() for kind in ("shape", "parts")}
    assert systems["shape"].state_names == systems["parts"].state_names
    assert len(systems["shape"].state_names) == 4 + 3 + 2 + 2   # ball, cardan: no more
    rng = np.random.default_rng(7)
    for _ in range(5):          # the same equations, to rounding
        x = systems["parts"].x0 + rng.normal(size=systems["parts"].x0.shape)
        expected = systems["parts"].rhs(0.0, x)
        np.testing.assert_allclose(systems["shape"].rhs(0.0, x), expected, rtol=0,
                                   atol=1e-12 * np.abs(expected).max())
    # and the same motion, to well within the integrator's own error (~1e-8 here)
    shape, parts = (kn.simulate(systems[kind], t_end=1.0, n_points=101, rtol=1e-11,
                                atol=1e-12, jit=False) for kind in ("shape", "parts"))
    np.testing.assert_allclose(shape.states, parts.states, rtol=0, atol=1e-7)
    for probe in ("pa", "pb", "pt", "pe"):
        for quantity in ("position", "force", "torque"):
            key = f"{probe}.{quantity}"
            expected = parts[key]
            if probe in ("pa", "pt") and quantity != "position":   # and the body's own
                expected = expected + parts[f"{probe}_body.{quantity}"]
            np.testing.assert_allclose(shape[key], expected, rtol=0,
                                       atol=1e-7 * max(1.0, np.abs(expected).max()))


def fourbar_scene(kind):
    """MSL-style four-bar of boxes (crank 0.3, coupler 1, rocker 0.8 over a ground link 1),
    its loop cut at joint C; force probes on both frames of every link."""
    m = kn.Model(f"fourbar_{kind}")
    m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    theta = 1.0
    guesses = fourbar_guesses(theta)
    m.add(mb.Revolute("A", q0=theta, qd0=0.5))
    m.add(mb.Revolute("B", q0_guess=guesses[0]))
    m.add(mb.Revolute("D", q0_guess=guesses[1]))
    m.add(mb.Revolute("C", q0_guess=guesses[2]))
    m.add(mb.FixedTranslation("base", r=[1.0, 0, 0]))
    frames = {}
    for name, length in (("crank", 0.3), ("coupler", 1.0), ("rocker", 0.8)):
        frames[name] = _shaped(m, name, kind, r=[length, 0, 0], r_shape=[0, 0, 0],
                               length_direction=[1, 0, 0], width_direction=[0, 1, 0],
                               length=length, width=0.04, height=0.02, density=ALUMINIUM)
    wiring = [("ground.frame", "A.frame_a"), ("A.frame_b", frames["crank"][0]),
              (frames["crank"][1], "B.frame_a"), ("B.frame_b", frames["coupler"][0]),
              ("ground.frame", "base.frame_a"), ("base.frame_b", "D.frame_a"),
              ("D.frame_b", frames["rocker"][0]), (frames["coupler"][1], "C.frame_a"),
              ("C.frame_b", frames["rocker"][1])]
    for a, b in wiring:
        m.connect(a, b)
    for name, (a, b) in frames.items():
        probes = [(f"{name}_a", a), (f"{name}_b", b)]
        if kind == "parts":
            probes.append((f"{name}_a_body", f"{name}_body.frame_a"))
        for probe, port in probes:
            m.add(kn.Probe(probe, quantities=["force", "torque"]))
            m.connect(f"{probe}.port", port)
    return m


def test_a_loop_of_boxes_moves_as_one_of_fixed_translations_with_rigid_bodies():
    shape, parts = (kn.simulate(fourbar_scene(kind), t_end=1.0, n_points=51, rtol=1e-12,
                                atol=1e-12, jit=False) for kind in ("shape", "parts"))
    assert shape.state_names == parts.state_names
    # the crank speed is the one independent speed; the other angles start the projection
    assert shape.state_names[0] == "A.q" and shape.state_names[-1] == "A.qd"
    # the integrator's own error is ~3e-9 here
    np.testing.assert_allclose(shape.states, parts.states, rtol=0, atol=1e-8)
    for name in ("crank", "coupler", "rocker"):
        for quantity in ("force", "torque"):
            for end in ("a", "b"):
                key = f"{name}_{end}.{quantity}"
                expected = parts[key]
                if end == "a":
                    expected = expected + parts[f"{name}_a_body.{quantity}"]
                np.testing.assert_allclose(shape[key], expected, rtol=0,
                                           atol=1e-6 * max(1.0, np.abs(expected).max()))


def test_rigid_body_looks_change_nothing():
    def scene(**looks):
        m = kn.Model("p")
        m.add(mb.Ground("ground"))
        m.add(mb.Revolute("j", q0=0.5))
        m.add(mb.RigidBody("b", mass=2.0, r_cm=[0, -0.4, 0], inertia=[0.1, 0.1, 0.1],
                           **looks))
        m.connect("ground.frame", "j.frame_a")
        m.connect("j.frame_b", "b.frame_a")
        return kn.simulate(m, t_end=1.0, n_points=11, jit=False).states
    plain = scene()
    np.testing.assert_array_equal(
        scene(shape="box", shape_size=[0.1, 0.8, 0.1], color="#c0ffee"), plain)
    np.testing.assert_array_equal(scene(shape="sphere", shape_size=[0.2, 0, 0]), plain)


# -- files, schema, refusals ------------------------------------------------------------------

def file_model():
    m = kn.Model("bodies", parameters={"L": 0.6, "W": 0.04})
    m.add(mb.Ground("ground"))
    m.add(mb.Revolute("j", q0=0.3))
    m.add(mb.BodyBox("box", r=[0, "-L", 0], width="W", inner_width="W/2",
                     width_direction=[1, 0, 0], density=2700, color="#3366CC"))
    m.add(mb.BodyCylinder("tube", r=["L/2", 0, 0], diameter="W", inner_diameter=0.01))
    m.add(mb.BodySphere("tip", diameter="2*W", color="#ff0000"))
    m.add(mb.RigidBody("weight", mass=1.0, shape="cylinder", shape_size=[0.1, 0.05, 0],
                       color="#00ff00"))
    for a, b in [("ground.frame", "j.frame_a"), ("j.frame_b", "box.frame_a"),
                 ("box.frame_b", "tube.frame_a"), ("tube.frame_b", "tip.frame_a"),
                 ("tube.frame_b", "weight.frame_a")]:
        m.connect(a, b)
    return m


def test_a_saved_model_loads_back_byte_identical(tmp_path):
    path, again = tmp_path / "bodies.json", tmp_path / "again.json"
    model = file_model()
    model.save(path)
    loaded = kn.load(path)
    loaded.save(again)
    assert again.read_bytes() == path.read_bytes()
    assert loaded.components["box"].given == model.components["box"].given
    assert loaded.components["weight"].shape == "cylinder"
    params = json.loads(path.read_text())["components"][2]["params"]
    assert "length" not in params and "width" in params      # defaults stay defaults
    assert loaded.compile().state_names == ["j.q", "j.qd"]


def test_the_schema_validates_a_file_of_them(tmp_path):
    schema = kn.schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    file_model().save(tmp_path / "m.json")
    data = json.loads((tmp_path / "m.json").read_text())
    assert list(validator.iter_errors(data)) == []
    for spoil in (lambda d: d["components"][5]["params"].update(shape="cone"),
                  lambda d: d["components"][2]["params"].update(color="blue"),
                  lambda d: d["components"][2]["params"].update(density=-1.0),
                  lambda d: d["components"][4]["params"].pop("diameter")):
        broken = json.loads(json.dumps(data))
        spoil(broken)
        assert list(validator.iter_errors(broken))
        with pytest.raises(kn.ModelError):
            kn.loads(json.dumps(broken))


REFUSALS = {
    "density": (lambda: mb.BodyBox("b", r=[1, 0, 0], density=-1),
                r"^b\.density = -1 kg/m\^3: must be >= 0"),
    "length": (lambda: mb.BodyBox("b", r=[1, 0, 0], length=-0.5),
               r"^b\.length = -0\.5 m: must be >= 0"),
    "inner_width": (lambda: mb.BodyBox("b", r=[1, 0, 0], width=0.1, inner_width=0.2),
                    r"^b\.inner_width = 0\.2 m: must be <= width \(0\.1 m\)$"),
    "inner_width_of_default_width": (                       # width: length / 20
        lambda: mb.BodyBox("b", r=[1, 0, 0], inner_width=0.2),
        r"^b\.inner_width = 0\.2 m: must be <= width \(0\.05 m\)$"),
    "inner_height": (lambda: mb.BodyBox("b", r=[1, 0, 0], height=0.01, inner_width=0.02,
                                        width=0.1),
                     r"^b\.inner_height = 0\.02 m: must be <= height \(0\.01 m\)$"),
    "length_direction": (lambda: mb.BodyBox("b", r=[1, 0, 0], length_direction=[0, 0, 0]),
                         r"^b\.length_direction: must not be the zero vector$"),
    "inner_diameter": (lambda: mb.BodyCylinder("c", r=[1, 0, 0], diameter=0.1,
                                               inner_diameter=0.12),
                       r"^c\.inner_diameter = 0\.12 m: must be <= diameter \(0\.1 m\)$"),
    "diameter": (lambda: mb.BodyCylinder("c", r=[1, 0, 0], diameter=-0.1),
                 r"^c\.diameter = -0\.1 m: must be >= 0"),
    "sphere_diameter": (lambda: mb.BodySphere("s", diameter=-1),
                        r"^s\.diameter = -1 m: must be >= 0"),
    "color": (lambda: mb.BodySphere("s", diameter=0.1, color="red"),
              r"^s\.color: must be a colour '#rrggbb', got 'red'$"),
    "shape": (lambda: mb.RigidBody("b", mass=1, shape="cube"),
              r"^b\.shape: must be one of box, cylinder, sphere, got 'cube'$"),
    "shape_suggested": (lambda: mb.RigidBody("b", mass=1, shape="boxx"),
                        r"\(did you mean 'box'\?\)"),
    "shape_size": (lambda: mb.RigidBody("b", mass=1, shape_size=[0.1, -0.2, 0]),
                   r"^b\.shape_size\[1\] = -0\.2 m: must be >= 0$"),
}


@pytest.mark.parametrize("build, message", [pytest.param(*v, id=k) for k, v in REFUSALS.items()])
def test_bad_values_are_refused_with_their_place(build, message):
    with pytest.raises(kn.ModelError, match=message):
        build()


def test_a_refused_assignment_leaves_the_body_as_it_was():
    box = mb.BodyBox("b", r=[1, 0, 0], width=0.1, inner_width=0.05)
    with pytest.raises(kn.ModelError, match=r"b\.inner_width = 0\.2 m: must be <= width"):
        box.inner_width = 0.2
    with pytest.raises(kn.ModelError, match=r"b\.inner_width = 0\.05 m: must be <= width"):
        box.width = 0.01
    assert box.inner_width == 0.05 and box.width == 0.1
    assert box.given == {"r": [1, 0, 0], "width": 0.1, "inner_width": 0.05}
    box.width = 0.2                                          # and a good one goes through
    assert box.given["width"] == 0.2


def test_sizes_of_expressions_are_checked_once_the_parameters_are_known():
    model = file_model()
    model.components["box"].inner_width = "2*W"             # accepted: W is not known here
    with pytest.raises(kn.ModelError, match=r"^box\.inner_width = 0\.08 m: must be <= width "
                                            r"\(0\.04 m\)$"):
        model.validate()
    model.components["box"].inner_width = "W/2"
    model.validate()
    model.parameters["W"] = 0.005           # the tube (inner diameter 0.01) gets too thin
    with pytest.raises(kn.ModelError, match=r"^tube\.inner_diameter = 0\.01 m: must be <= "
                                            r"diameter \(0\.005 m\)$"):
        model.validate()


def test_a_file_names_the_place_of_a_bad_size(tmp_path):
    path = tmp_path / "m.json"
    file_model().save(path)
    data = json.loads(path.read_text())
    data["components"][3]["params"]["inner_diameter"] = "2*W"
    with pytest.raises(kn.ModelError, match=r'components\[3\] "tube" params\.inner_diameter = '
                                            r"0\.08 m: must be <= diameter \(0\.04 m\)"):
        kn.loads(json.dumps(data)).validate()


# -- documentation ----------------------------------------------------------------------------

@pytest.mark.parametrize("cls", [mb.RigidBody, mb.BodyBox, mb.BodyCylinder, mb.BodySphere],
                         ids=lambda c: c.__name__)
def test_docstrings_list_every_parameter_with_its_unit(cls):
    doc = cls.__doc__
    lines = {line.split(" : ")[0].strip(): line for line in doc.splitlines() if " : " in line}
    assert list(lines) == list(cls.params), "the docstring lists the parameters in order"
    for name, spec in cls.params.items():
        if spec.unit:
            assert lines[name].split(" : ")[1].startswith(spec.unit), name
    assert "kg" in lines["mass" if "mass" in lines else "density"]
