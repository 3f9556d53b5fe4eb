"""Model building and validation: every refusal is a ModelError naming its place."""

import copy

import pytest

import kinetwork as kn
from scenes import double_pendulum

mb, rot = kn.multibody, kn.rotational


def test_ports_as_attributes_or_strings(seed_model):
    model = seed_model
    n = len(model.connections)
    model.add(kn.Probe("p3", quantities=["position"]))
    model.connect(model.components["p3"].port, "mass2.frame_a")
    assert len(model.connections) == n + 1
    assert model.validate().dof == 2


def snapshot(model):
    return (list(model.components), [(a.path, b.path) for a, b in model.connections],
            dict(model.parameters))


@pytest.mark.parametrize("action, match", [
    (lambda m: m.add(mb.RigidBody("mass1", mass=1.0)), "duplicate component name 'mass1'"),
    (lambda m: m.connect("mass1.frame_a", "spring.flange_a"), "different domains"),
    (lambda m: m.connect("mass1.frame_x", "ground.frame"), "no port 'frame_x'.*frame_a"),
    (lambda m: m.connect("mas1.frame_a", "ground.frame"), "did you mean 'mass1'"),
    (lambda m: m.connect("ground.frame", "ground.frame"), "to itself"),
    (lambda m: m.connect("ground.frame", "shoulder.frame_a"), "already connected"),
    (lambda m: m.connect(mb.Ground("other").frame, "shoulder.frame_a"), "not in model"),
    (lambda m: m.connect("groundframe", "shoulder.frame_a"), "expected 'component.port'"),
    (lambda m: m.set_parameter("t", 1.0), "reserved"),
    (lambda m: m.set_parameter("k", float("nan")), "finite"),
    (lambda m: m.add("mass3"), "expects a component"),
])
def test_bad_edits_refused_and_model_unchanged(seed_model, action, match):
    before = snapshot(seed_model)
    with pytest.raises(kn.ModelError, match=match):
        action(seed_model)
    assert snapshot(seed_model) == before


@pytest.mark.parametrize("make, match", [
    (lambda: mb.RigidBody("m", mass=-1.0), r"m.mass = -1.0 kg: must be >= 0"),
    (lambda: mb.RigidBody("m", mass=float("nan")), "m.mass: must be finite"),
    (lambda: mb.RigidBody("m", mass=1, inertia=[[1, 0], [0, 1]]), "m.inertia: must have 3"),
    (lambda: mb.Revolute("j", axis=[0, 0, 0]), "j.axis: must not be the zero vector"),
    (lambda: mb.Revolute("j", axis=[0, 0, "__import__('os')"]), "not allowed"),
    (lambda: mb.Revolute("j", axis=[0, 0, "().__class__"]), "not allowed"),
    (lambda: mb.Revolute("j", q0="sin(t)"), "time 't' is not allowed"),
    (lambda: mb.Revolute("j", q0="1 +"), "cannot parse"),
    (lambda: mb.Revolute("j", q0="foo(2)"), "call of 'foo'"),
    (lambda: mb.Revolute("j", axs=[1, 0, 0]), "did you mean 'axis'"),
    (lambda: mb.Revolute("2j"), "must be an identifier"),
    (lambda: rot.SpringDamper("s", c=1.0), "s.d: a value is required"),
    (lambda: kn.Probe("p", quantities=["angel"]), "did you mean 'angle'"),
    (lambda: mb.Revolute("j", cut="yes"), "true or false"),
])
def test_bad_parameters_refused(make, match):
    with pytest.raises(kn.ModelError, match=match):
        make()


def test_every_bad_entry_of_a_vector_reported():
    with pytest.raises(kn.ModelError) as info:
        mb.FixedTranslation("f", r=["1 +", 0, "().__class__"])
    assert [p.split(":")[0] for p in info.value.problems] == ["f.r[0]", "f.r[2]"]


def test_every_problem_reported_at_once():
    with pytest.raises(kn.ModelError) as info:
        mb.RigidBody("m", mass=-1.0, r_cm=[0, 0], inertia="x")
    assert len(info.value.problems) == 3


def broken(edit):
    model = double_pendulum()
    edit(model)
    return model


def drop(model, a, b):
    model.connections = [c for c in model.connections
                         if {c[0].path, c[1].path} != {a, b}]


@pytest.mark.parametrize("edit, match", [
    (lambda m: drop(m, "shoulder.frame_b", "mass1.frame_a"), "mass1.frame_a .* not connected"),
    (lambda m: m.add(mb.Ground("ground2")), "exactly one multibody.Ground, found 2"),
    (lambda m: m.components.pop("ground") and drop(m, "ground.frame", "shoulder.frame_a"),
     "exactly one multibody.Ground, found 0"),
    (lambda m: (m.add(mb.RigidBody("floating", mass=1.0)),
                m.add(mb.FixedTranslation("arm", r=[1, 0, 0])),
                m.connect("floating.frame_a", "arm.frame_a")),
     "floating is not connected to the ground"),
    (lambda m: m.add(kn.Probe("lonely")), "lonely.port is wired to nothing"),
    (lambda m: (m.add(kn.Probe("wrong", quantities=["angle"])),
                m.connect("wrong.port", "mass1.frame_a")), "'angle' is not a quantity of a frame"),
    # two torques on a flange with no inertia, spring or damper cannot balance (a spring in
    # series with a damper can: that is a Maxwell element, see tests/equations/test_network.py)
    (lambda m: (m.add(rot.Torque("free", tau=1.0)), m.add(rot.Torque("free2", tau=2.0)),
                m.connect("free.flange", "free2.flange")), "has no defined rotational"),
    (lambda m: (m.add(rot.Fixed("lock")), m.connect("lock.flange", "elbow.axis")),
     "rigidly ties joint flange elbow.axis"),
    (lambda m: m.components["mass1"].set_param("mass", "m9"), "unknown name 'm9'"),
    (lambda m: m.components["mass1"].set_param("mass", "m1/(L1-1)"), "cannot be evaluated"),
    (lambda m: m.components["mass1"].set_param("mass", "m1-2"), "mass1.mass = -1.0 kg"),
    # a component deleted by hand, its connections left behind: named, not a KeyError
    (lambda m: m.components.pop("mass1"), r"connections\[1\] shoulder.frame_b - "
                                          r"mass1.frame_a: component 'mass1' is not in the "
                                          r"model any more \(remove its connections too\)"),
    (lambda m: m.components.pop("probe2"), "component 'probe2' is not in the model any more"),
])
def test_structural_problems(edit, match):
    model = broken(edit)
    with pytest.raises(kn.ModelError, match=match):
        model.validate()


def test_validate_does_not_change_model(seed_model):
    before = copy.deepcopy(snapshot(seed_model))
    seed_model.validate()
    assert snapshot(seed_model) == before


def test_param_overrides_checked(seed_model):
    system = seed_model.compile()
    with pytest.raises(kn.ModelError, match="'cc' is no model parameter .did you mean 'c'."):
        kn.simulate(system, params={"cc": 1.0})
    with pytest.raises(kn.ModelError, match=r"mass1.mass = -2.0 kg: must be >= 0"):
        kn.simulate(system, params={"m1": -2.0})
    with pytest.raises(kn.ModelError, match="method 'rk4'"):
        kn.simulate(system, method="rk4")
    with pytest.raises(kn.ModelError, match="n_points"):
        kn.simulate(system, n_points=1)
