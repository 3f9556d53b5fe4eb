"""Signal descriptors (kinetwork/equations/signals.py): what each probe of each domain records,
named, with its unit and shape, from the model to the results."""

import casadi as ca
import numpy as np
import pytest

import kinetwork as kn
from kinetwork.equations.signals import Signal

mb = kn.multibody


@pytest.fixture(scope="module")
def model():
    """A hinge about z carrying a slider along x with a body: probes on a rotational flange,
    a translational flange, a frame and a signal."""
    m = kn.Model("signals")
    m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    m.add(mb.Revolute("hinge", axis=[0, 0, 1], q0=0.3))
    m.add(mb.Prismatic("slide", axis=[1, 0, 0], q0=0.5))
    m.add(mb.RigidBody("body", mass=1.0, r_cm=[0.5, 0, 0], inertia=[0.1, 0.1, 0.1]))
    m.add(kn.translational.SpringDamper("sd", c=10.0, d=1.0))
    m.add(kn.rotational.AngleSensor("sensor"))
    m.add(kn.Probe("rot", quantities=["angle", "torque"]))
    m.add(kn.Probe("trans"))                                  # all of its domain
    m.add(kn.Probe("frame", quantities=["position", "orientation", "angular_velocity"]))
    m.add(kn.Probe("signal"))
    for a, b in [("ground.frame", "hinge.frame_a"), ("hinge.frame_b", "slide.frame_a"),
                 ("slide.frame_b", "body.frame_a"), ("sd.flange_a", "slide.support"),
                 ("sd.flange_b", "slide.axis"), ("sensor.flange", "hinge.axis"),
                 ("rot.port", "hinge.axis"), ("trans.port", "slide.axis"),
                 ("frame.port", "body.frame_a"), ("signal.port", "sensor.y")]:
        m.connect(a, b)
    return m


EXPECTED = [
    Signal("rot.angle", "rad", (), "rot", "angle", "hinge.axis"),
    Signal("rot.torque", "N*m", (), "rot", "torque", "hinge.axis"),
    Signal("trans.position", "m", (), "trans", "position", "slide.axis"),
    Signal("trans.velocity", "m/s", (), "trans", "velocity", "slide.axis"),
    Signal("trans.acceleration", "m/s^2", (), "trans", "acceleration", "slide.axis"),
    Signal("trans.force", "N", (), "trans", "force", "slide.axis"),
    Signal("frame.position", "m", (3,), "frame", "position", "body.frame_a"),
    Signal("frame.orientation", "", (3, 3), "frame", "orientation", "body.frame_a"),
    Signal("frame.angular_velocity", "rad/s", (3,), "frame", "angular_velocity",
           "body.frame_a"),
    Signal("signal.value", "rad", (), "signal", "value", "sensor.y"),     # an angle sensor's
]


def test_each_probe_quantity_has_its_descriptor(model):
    system = model.compile()
    assert system.signals == EXPECTED                      # the expression is not compared
    assert all(sig.expression is None for sig in system.signals)      # kept out of results
    assert system.probe_targets == {"rot": "hinge.axis", "trans": "slide.axis",
                                    "frame": "body.frame_a", "signal": "sensor.y"}


def test_the_descriptors_travel_to_the_results(model):
    res = kn.simulate(model, t_end=1.0, n_points=11)
    assert list(res.signals.values()) == EXPECTED
    assert {name: res[name].shape[1:] for name in res.signals} == {
        sig.name: sig.shape for sig in EXPECTED}
    q, s = res["hinge.q"], res["slide.q"]
    np.testing.assert_allclose(res["rot.angle"], q, atol=1e-12)
    np.testing.assert_allclose(res["signal.value"], q, atol=1e-12)
    np.testing.assert_allclose(res["trans.position"], s, atol=1e-12)
    np.testing.assert_allclose(res["frame.position"],
                               np.column_stack([s * np.cos(q), s * np.sin(q), 0 * q]),
                               atol=1e-12)
    np.testing.assert_allclose(res["frame.orientation"][:, :2, 0],
                               np.column_stack([np.cos(q), np.sin(q)]), atol=1e-12)
    np.testing.assert_allclose(res["frame.angular_velocity"][:, 2], res["hinge.qd"],
                               atol=1e-12)


def test_column_names_and_sizes_follow_the_shape():
    assert EXPECTED[0].column_names() == ["rot.angle"] and EXPECTED[0].size == 1
    assert EXPECTED[6].column_names() == [f"frame.position[{i}]" for i in range(3)]
    assert EXPECTED[7].size == 9
    assert EXPECTED[7].column_names()[:4] == ["frame.orientation[0,0]",
                                              "frame.orientation[0,1]",
                                              "frame.orientation[0,2]",
                                              "frame.orientation[1,0]"]


def test_a_matrix_flattens_row_major_as_its_columns_are_named():
    matrix = ca.SX(ca.DM(np.arange(9.0).reshape(3, 3)))
    sig = Signal("f.orientation", "", (3, 3), "f", "orientation", "b.frame_a", matrix)
    np.testing.assert_array_equal(np.array(ca.evalf(sig.flat())).ravel(), np.arange(9.0))
    assert sig.described().expression is None and sig.described() == sig
