"""BodyShape (MSL's Parts.BodyShape) and the Ground's gravity field parameters.

A BodyShape is a FixedTranslation that carries a RigidBody on its frame_a: in motion it must
be exactly that pair, hung from frame_a or from frame_b, and a BodyShape hung from frame_b
the closed-form compound pendulum, its pivot carrying m (a_c - g).
"""

import json

import jsonschema
import numpy as np
import pytest

import kinetwork as kn

mb = kn.multibody
R = [0.2, -0.9, 0.3]
R_CM = [0.1, -0.4, 0.05]
INERTIA = [[0.05, 0.004, -0.002], [0.004, 0.03, 0.001], [-0.002, 0.001, 0.06]]


def chain(shaped, from_b=False):
    """ground -> revolute -> the body (a BodyShape, or a FixedTranslation carrying a
    RigidBody) -> revolute -> a small RigidBody; ``from_b``: the body hangs from frame_b."""
    model = kn.Model("chain")
    model.add(mb.Ground("ground", gravity=[0.3, -9.81, 0.5]))
    model.add(mb.Revolute("j1", axis=[0.2, 0.1, 1.0], q0=0.4, qd0=-0.3))
    model.add(mb.Revolute("j2", axis=[1.0, 0.5, 0.0], q0=-1.1, qd0=0.8))
    model.add(mb.RigidBody("tip", mass=0.7, r_cm=[0.0, -0.2, 0.1], inertia=[0.01, 0.02, 0.015]))
    if shaped:
        model.add(mb.BodyShape("body", r=R, mass=2.5, r_cm=R_CM, inertia=INERTIA))
    else:
        model.add(mb.FixedTranslation("body", r=R))
        model.add(mb.RigidBody("body_mass", mass=2.5, r_cm=R_CM, inertia=INERTIA))
        model.connect("body.frame_a", "body_mass.frame_a")
    near, far = ("body.frame_b", "body.frame_a") if from_b else ("body.frame_a", "body.frame_b")
    for a, b in [("ground.frame", "j1.frame_a"), ("j1.frame_b", near), (far, "j2.frame_a"),
                 ("j2.frame_b", "tip.frame_a")]:
        model.connect(a, b)
    for port in ("j1.frame_a", "j2.frame_a"):
        name = f"cut_{port.split('.')[0]}"
        model.add(kn.Probe(name, quantities=["force", "torque"]))
        model.connect(f"{name}.port", port)
    return model


@pytest.mark.parametrize("from_b", [False, True], ids=["from_frame_a", "from_frame_b"])
def test_body_shape_is_a_fixed_translation_with_a_rigid_body(from_b):
    shaped, parts = chain(True, from_b).compile(), chain(False, from_b).compile()
    assert shaped.state_names == parts.state_names == ["j1.q", "j2.q", "j1.qd", "j2.qd"]
    rng = np.random.default_rng(3)
    for _ in range(3):
        x = rng.uniform(-2, 2, 4)
        np.testing.assert_allclose(shaped.mass_matrix(x[:2]), parts.mass_matrix(x[:2]),
                                   rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(shaped.rhs(0.0, x), parts.rhs(0.0, x), rtol=1e-12,
                                   atol=1e-12)
        np.testing.assert_allclose(shaped.outputs(0.0, x[None, :]),
                                   parts.outputs(0.0, x[None, :]), rtol=1e-11, atol=1e-11)


def test_body_shape_hung_from_frame_b_is_the_compound_pendulum():
    """Pivot at frame_b, frame_a L below it, centre of mass d = L - 0.3 L below the pivot:
    q'' = -m g d sin q / (I_zz + m d^2), and the pivot carries m (a_c - g)."""
    L, m, izz, g = 0.8, 1.6, 0.09, 9.81
    model = kn.Model("pendulum")
    model.add(mb.Ground("ground", gravity=[0, -g, 0]))
    model.add(mb.Revolute("pivot"))
    model.add(mb.BodyShape("rod", r=[0, L, 0], mass=m, r_cm=[0, 0.3 * L, 0],
                           inertia=[0.05, 0.05, izz]))
    model.add(kn.Probe("cut", quantities=["force"]))
    for a, b in [("ground.frame", "pivot.frame_a"), ("pivot.frame_b", "rod.frame_b"),
                 ("cut.port", "pivot.frame_a")]:
        model.connect(a, b)
    system = model.compile()
    d = 0.7 * L
    for q, qd in [(0.0, 0.0), (0.9, -1.2), (2.8, 0.5)]:
        qdd = -m * g * d * np.sin(q) / (izz + m * d**2)
        assert system.rhs(0.0, [q, qd])[1] == pytest.approx(qdd, rel=1e-12)
        c = d * np.array([np.sin(q), -np.cos(q), 0.0])
        a_c = d * np.array([qdd * np.cos(q) - qd**2 * np.sin(q),
                            qdd * np.sin(q) + qd**2 * np.cos(q), 0.0])
        assert np.linalg.norm(c) == pytest.approx(d)
        force = np.asarray(system.outputs(0.0, np.array([[q, qd]])), dtype=float).ravel()
        np.testing.assert_allclose(force, m * (a_c - [0, -g, 0]), rtol=1e-12, atol=1e-12)


def test_body_shape_on_the_ground_costs_no_state():
    model = kn.Model("welded")
    model.add(mb.Ground("ground"))
    model.add(mb.BodyShape("base", r=[1, 0, 0], mass=3.0))
    model.add(mb.Revolute("j"))
    model.add(mb.RigidBody("b", mass=1.0, r_cm=[0, -1, 0]))
    for a, b in [("ground.frame", "base.frame_a"), ("base.frame_b", "j.frame_a"),
                 ("j.frame_b", "b.frame_a")]:
        model.connect(a, b)
    assert model.compile().state_names == ["j.q", "j.qd"]


def file_model():
    model = kn.Model("shapes", parameters={"L": 0.5})
    model.add(mb.Ground("ground", gravity_type="point", mue=5.0))
    model.add(mb.FixedTranslation("post", r=[3.0, 0, 0]))
    model.add(mb.Revolute("j"))
    model.add(mb.BodyShape("rod", r=[0, "-L", 0], mass=1.0, r_cm=[0, "-L/2", 0],
                           inertia=[0.02, 0.001, 0.02], shape="box", color="#336699"))
    for a, b in [("ground.frame", "post.frame_a"), ("post.frame_b", "j.frame_a"),
                 ("j.frame_b", "rod.frame_a")]:
        model.connect(a, b)
    return model


def test_a_saved_model_loads_back_byte_identical(tmp_path):
    path, again = tmp_path / "m.json", tmp_path / "again.json"
    file_model().save(path)
    loaded = kn.load(path)
    loaded.save(again)
    assert again.read_bytes() == path.read_bytes()
    data = json.loads(path.read_text())
    assert data["components"][0]["params"] == {"gravity_type": "point", "mue": 5.0}
    assert list(data["components"][3]["params"]) == ["r", "mass", "r_cm", "inertia", "shape",
                                                     "color"]
    assert loaded.compile().state_names == ["j.q", "j.qd"]


def test_the_schema_validates_a_file_of_them(tmp_path):
    validator = jsonschema.Draft202012Validator(kn.schema())
    file_model().save(tmp_path / "m.json")
    data = json.loads((tmp_path / "m.json").read_text())
    assert list(validator.iter_errors(data)) == []
    for spoil in (lambda d: d["components"][0]["params"].update(gravity_type="radial"),
                  lambda d: d["components"][0]["params"].update(mue=-1.0),
                  lambda d: d["components"][3]["params"].update(shape="cone"),
                  lambda d: d["components"][3]["params"].pop("mass")):
        broken = json.loads(json.dumps(data))
        spoil(broken)
        assert list(validator.iter_errors(broken))
        with pytest.raises(kn.ModelError):
            kn.loads(json.dumps(broken))


REFUSALS = {
    "mass": (lambda: mb.BodyShape("s", r=[1, 0, 0], mass=-1), r"^s\.mass = -1 kg: must be >= 0"),
    "mass_required": (lambda: mb.BodyShape("s", r=[1, 0, 0]),
                      r"^s\.mass: a value is required"),
    "shape": (lambda: mb.BodyShape("s", r=[1, 0, 0], mass=1, shape="cone"),
              r"^s\.shape: must be one of box, cylinder, sphere, got 'cone'"),
    "shape_size": (lambda: mb.BodyShape("s", r=[1, 0, 0], mass=1, shape_size=[1, -0.1, 0]),
                   r"^s\.shape_size\[1\] = -0\.1 m: must be >= 0$"),
    "gravity_type": (lambda: mb.Ground("g", gravity_type="radial"),
                     r"^g\.gravity_type: must be one of uniform, point, expression, got 'radial'"),
    "mue": (lambda: mb.Ground("g", mue=-2.0), r"^g\.mue = -2(\.0)? m\^3/s\^2: must be >= 0"),
}


@pytest.mark.parametrize("build, message", [pytest.param(*v, id=k) for k, v in REFUSALS.items()])
def test_bad_values_are_refused_with_their_place(build, message):
    with pytest.raises(kn.ModelError, match=message):
        build()


def test_an_inertia_that_is_not_a_body_s_is_refused_at_validation():
    model = file_model()
    model.components["rod"].inertia = [[0.02, 0.01, 0], [0.0, 0.001, 0], [0, 0, 0.02]]
    with pytest.raises(kn.ModelError, match=r"rod\.inertia: must be symmetric"):
        model.validate()
    model.components["rod"].inertia = [0.02, -0.5, 0.02]
    with pytest.raises(kn.ModelError, match=r"rod\.inertia: must be positive semi-definite"):
        model.validate()


def test_ground_fields():
    uniform = mb.Ground("g", gravity=[0, 0, -9.8])
    np.testing.assert_array_equal(np.asarray(uniform.gravity_at(np.ones((3, 1)))).ravel(),
                                  [0, 0, -9.8])
    point = mb.Ground("g", gravity_type="point", mue=2.0)
    assert point.uniform_gravity() is None
    r = np.array([[1.0], [2.0], [-2.0]])
    np.testing.assert_allclose(np.asarray(point.gravity_at(r)).ravel(),
                               -2.0 / 9.0 * r.ravel() / 3.0, rtol=1e-15)
    assert mb.Ground("g").mue == 3.986004418e14


@pytest.mark.parametrize("cls", [mb.BodyShape, mb.Ground, mb.Force, mb.Torque,
                                 mb.ForceAndTorque], ids=lambda c: c.__name__)
def test_docstrings_list_every_parameter_with_its_unit(cls):
    doc = cls.__doc__
    lines = {line.split(" : ")[0].strip(): line for line in doc.splitlines() if " : " in line}
    assert list(lines) == list(cls.params), "the docstring lists the parameters in order"
    for name, spec in cls.params.items():
        if spec.unit:
            text = lines[name].split(" : ")[1]
            assert text.startswith((spec.unit, f"expression in {spec.unit}")), name
