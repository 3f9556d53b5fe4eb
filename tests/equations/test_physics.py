"""Physics checks against conservation laws and exact solutions (not against ourselves)."""

import numpy as np
import pytest

import kinetwork as kn
from scenes import double_pendulum

TIGHT = {"rtol": 1e-10, "atol": 1e-12}


def chain_with_probes(n_links, damped=False, seed=0):
    """A spatial chain of revolutes on skew axes; each body sits on a probed frame at its CM."""
    rng = np.random.default_rng(seed)
    g = [0.3, -9.81, 0.7]
    m = kn.Model("chain")
    m.add(kn.multibody.Ground("ground", gravity=g))
    prev = "ground.frame"
    bodies = []
    for i in range(n_links):
        axis = rng.normal(size=3)
        m.add(kn.multibody.Revolute(f"j{i}", axis=axis.tolist(), q0=float(rng.uniform(-1, 1)),
                                    qd0=float(rng.uniform(-1, 1))))
        m.add(kn.multibody.FixedTranslation(f"to_cm{i}", r=rng.uniform(-0.5, 0.5, 3).tolist()))
        A = rng.normal(size=(3, 3))
        S = (A @ A.T + 0.1 * np.eye(3)) * 0.05     # second moments of a mass distribution:
        inertia = np.trace(S) * np.eye(3) - S       # a physical tensor (triangle inequality)
        mass = float(rng.uniform(0.5, 2.0))
        m.add(kn.multibody.RigidBody(f"b{i}", mass=mass, inertia=inertia.tolist()))
        m.add(kn.Probe(f"p{i}", quantities=["position", "velocity", "orientation",
                                            "angular_velocity"]))
        m.add(kn.multibody.FixedTranslation(f"link{i}", r=rng.uniform(-1, 1, 3).tolist()))
        m.connect(prev, f"j{i}.frame_a")
        m.connect(f"j{i}.frame_b", f"to_cm{i}.frame_a")
        m.connect(f"to_cm{i}.frame_b", f"b{i}.frame_a")
        m.connect(f"p{i}.port", f"to_cm{i}.frame_b")
        m.connect(f"j{i}.frame_b", f"link{i}.frame_a")
        prev = f"link{i}.frame_b"
        bodies.append((mass, inertia))
        if damped:
            m.add(kn.rotational.Damper(f"d{i}", d=0.5))
            m.connect(f"d{i}.flange_a", f"j{i}.support")
            m.connect(f"d{i}.flange_b", f"j{i}.axis")
    return m, bodies, np.array(g)


def energy(res, bodies, g):
    """Kinetic plus potential energy from probe kinematics (world frame)."""
    total = np.zeros(len(res.t))
    for i, (mass, inertia) in enumerate(bodies):
        v, w = res[f"p{i}.velocity"], res[f"p{i}.angular_velocity"]
        R, r = res[f"p{i}.orientation"], res[f"p{i}.position"]
        I_world = R @ inertia @ np.transpose(R, (0, 2, 1))
        total += 0.5 * mass * np.sum(v * v, axis=1)
        total += 0.5 * np.einsum("ni,nij,nj->n", w, I_world, w)
        total -= mass * r @ g
    return total


@pytest.mark.parametrize("method", ["cvodes", "idas", "DOP853"])
def test_energy_conserved_spatial_chain(method):
    model, bodies, g = chain_with_probes(4)
    res = kn.simulate(model, t_end=5.0, n_points=501, method=method, **TIGHT)
    e = energy(res, bodies, g)
    scale = np.max(np.abs(e - e.mean())) + np.abs(e).max()
    assert np.max(np.abs(e - e[0])) < 1e-7 * scale


def test_energy_decreases_with_damping():
    model, bodies, g = chain_with_probes(3, damped=True)
    res = kn.simulate(model, t_end=5.0, n_points=501, **TIGHT)
    e = energy(res, bodies, g)
    assert np.all(np.diff(e) <= 1e-9 * np.abs(e).max())
    assert e[-1] < e[0] - 1e-3


def pendulum(length=2.0, mass=1.5, q0=0.01, inertia=0.0, g=9.81):
    m = kn.Model("pendulum", parameters={"L": length})
    m.add(kn.multibody.Ground("ground", gravity=[0, -g, 0]))
    m.add(kn.multibody.Revolute("pivot", axis=[0, 0, 1], q0=q0))
    m.add(kn.multibody.RigidBody("bob", mass=mass, r_cm=[0, "-L", 0],
                                 inertia=[0, 0, inertia]))
    m.connect("ground.frame", "pivot.frame_a")
    m.connect("pivot.frame_b", "bob.frame_a")
    return m


def test_small_angle_period():
    length, g, mass, inertia = 2.0, 9.81, 1.5, 0.3
    res = kn.simulate(pendulum(length, mass, 1e-4, inertia, g), t_end=20.0, n_points=20001,
                      **TIGHT)
    q = res["pivot.q"]
    up = np.where((q[:-1] < 0) & (q[1:] >= 0))[0]
    crossings = res.t[up] - q[up] * (res.t[up + 1] - res.t[up]) / (q[up + 1] - q[up])
    period = np.mean(np.diff(crossings))
    expected = 2 * np.pi * np.sqrt((mass * length**2 + inertia) / (mass * g * length))
    assert period == pytest.approx(expected, rel=1e-6)


def oscillator(c=40.0, d=1.5, mass=2.0, s0=0.3, spring="SpringDamper"):
    """A mass on a prismatic joint, held by a translational spring-damper; no gravity."""
    m = kn.Model("oscillator")
    m.add(kn.multibody.Ground("ground", gravity=[0, 0, -9.81]))
    m.add(kn.multibody.Prismatic("slider", axis=[1, 0, 0], q0=s0))
    m.add(kn.multibody.RigidBody("mass", mass=mass))
    m.connect("ground.frame", "slider.frame_a")
    m.connect("slider.frame_b", "mass.frame_a")
    m.add(kn.Probe("probe"))
    m.connect("probe.port", "slider.axis")
    if spring == "SpringDamper":
        m.add(kn.translational.SpringDamper("sd", c=c, d=d))
        pairs = [("sd", "flange_a", "flange_b")]
    else:
        m.add(kn.translational.Spring("k", c=c))
        m.add(kn.translational.Damper("b", d=d))
        pairs = [("k", "flange_a", "flange_b"), ("b", "flange_a", "flange_b")]
    for name, a, b in pairs:
        m.connect(f"{name}.{a}", "slider.support")
        m.connect(f"{name}.{b}", "slider.axis")
    return m


def test_damped_oscillator_exact():
    c, d, mass, s0 = 40.0, 1.5, 2.0, 0.3
    res = kn.simulate(oscillator(c, d, mass, s0), t_end=5.0, n_points=501, **TIGHT)
    zeta_w, wd = d / (2 * mass), np.sqrt(c / mass - (d / (2 * mass)) ** 2)
    t = res.t
    x = s0 * np.exp(-zeta_w * t) * (np.cos(wd * t) + zeta_w / wd * np.sin(wd * t))
    v = -s0 * np.exp(-zeta_w * t) * (zeta_w**2 + wd**2) / wd * np.sin(wd * t)
    np.testing.assert_allclose(res["probe.position"], x, atol=1e-8)
    np.testing.assert_allclose(res["probe.velocity"], v, atol=1e-7)
    np.testing.assert_allclose(res["probe.acceleration"], -(c * x + d * v) / mass, atol=1e-6)
    np.testing.assert_allclose(res["probe.force"], -(c * x + d * v), atol=1e-6)


def test_spring_damper_equals_spring_plus_damper():
    a = kn.simulate(oscillator(spring="SpringDamper"), t_end=3.0, **TIGHT)
    b = kn.simulate(oscillator(spring="parallel"), t_end=3.0, **TIGHT)
    np.testing.assert_allclose(a.states, b.states, atol=1e-9)
    np.testing.assert_allclose(a["probe.force"], b["probe.force"], atol=1e-8)


def test_torque_source_in_time_exact():
    """A free rotor driven by A*sin(w*t): q = A/(J w) (t - sin(w t)/w)."""
    m = kn.Model("rotor", parameters={"A": 2.0, "w": 3.0})
    m.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    m.add(kn.multibody.Revolute("hub", axis=[0, 1, 0]))
    m.add(kn.multibody.RigidBody("disc", mass=3.0, inertia=[0.2, 0.4, 0.2]))   # a disc
    m.add(kn.rotational.Torque("drive", tau="A*sin(w*t)"))
    m.add(kn.Probe("probe", quantities=["angle", "torque"]))
    m.connect("ground.frame", "hub.frame_a")
    m.connect("hub.frame_b", "disc.frame_a")
    m.connect("drive.flange", "hub.axis")
    m.connect("probe.port", "hub.axis")
    res = kn.simulate(m, t_end=4.0, n_points=401, params={"A": 1.5}, **TIGHT)
    A, w, J, t = 1.5, 3.0, 0.4, res.t
    np.testing.assert_allclose(res["probe.angle"], A / (J * w) * (t - np.sin(w * t) / w),
                               atol=1e-8)
    np.testing.assert_allclose(res["probe.torque"], A * np.sin(w * t), atol=1e-12)


def test_parameters_change_without_recompiling(seed_model):
    system = seed_model.compile()
    changed = kn.simulate(system, t_end=3.0, params={"c": 5.0, "m2": 2.5}, **TIGHT)
    rebuilt = kn.simulate(double_pendulum(c=5.0, m2=2.5), t_end=3.0, **TIGHT)
    default = kn.simulate(system, t_end=3.0, **TIGHT)
    np.testing.assert_allclose(changed.states, rebuilt.states, atol=1e-9)
    assert np.max(np.abs(changed.states - default.states)) > 1e-3


def test_welded_body_has_no_state():
    m = kn.Model("welded")
    m.add(kn.multibody.Ground("ground"))
    m.add(kn.multibody.FixedRotation("tilt", angle=0.3, r=[1, 0, 0]))
    m.add(kn.multibody.RigidBody("block", mass=2.0))
    m.add(kn.Probe("where", quantities=["position", "velocity"]))
    m.connect("ground.frame", "tilt.frame_a")
    m.connect("tilt.frame_b", "block.frame_a")
    m.connect("where.port", "tilt.frame_b")
    system = m.compile()
    assert system.state_names == []
    res = kn.simulate(system, t_end=1.0, n_points=11)
    assert res.states.shape == (11, 0)
    np.testing.assert_allclose(res["where.position"], np.tile([1, 0, 0], (11, 1)))
    np.testing.assert_allclose(res["where.velocity"], 0)


def test_reversed_joint_mirrors_coordinate():
    """A revolute wired frame_b-to-ground turns the other way: q_reversed = -q."""
    def build(reverse):
        m = pendulum(q0=0.0)
        m.components["pivot"].q0 = -0.4 if reverse else 0.4
        if reverse:
            m.connections = [(m.port("pivot.frame_b"), m.port("ground.frame")),
                             (m.port("pivot.frame_a"), m.port("bob.frame_a"))]
        return m
    a = kn.simulate(build(False), t_end=2.0, **TIGHT)
    b = kn.simulate(build(True), t_end=2.0, **TIGHT)
    np.testing.assert_allclose(b.states, -a.states, atol=1e-9)


def test_failure_keeps_partial_results():
    """A torque 1/(1-t) blows up at t = 1: the error carries the run up to there."""
    m = pendulum()
    m.add(kn.rotational.Torque("blowup", tau="1/(1-t)**3"))
    m.connect("blowup.flange", "pivot.axis")
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(m, t_end=2.0, n_points=201, method="cvodes", **TIGHT)
    err = info.value
    assert 0.9 <= err.t_reached <= 1.0
    assert "blow up" in str(err) and "Consult" not in str(err)
    part = err.results
    assert part.t[-1] == pytest.approx(err.t_reached)
    good = kn.simulate(m, t_end=0.9, n_points=91, method="DOP853", **TIGHT)
    n = len(good.t)
    np.testing.assert_allclose(part.states[:n], good.states, rtol=1e-6, atol=1e-8)
