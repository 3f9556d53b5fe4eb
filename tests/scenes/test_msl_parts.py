"""MSL's examples of Rotor1D, RollingWheel, LineForceWithTwoMasses and JointRRR loops as
example models (``models/*.json``), each against a reference independent of kinetwork:
closed forms, MSL's own claims (two ways of one scene move alike) and an independent
Lagrangian."""

import pathlib

import numpy as np

import kinetwork as kn
from kinetwork.animation.scene import animation_data
from scenes.line_masses import Scene, msl_cut_forces, solve

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def run(name, t_end, n=21, **kw):
    return kn.simulate(kn.load(MODELS / f"{name}.json"), t_end=t_end, n_points=n, rtol=1e-11,
                       atol=1e-12, jit=False, **kw)


def test_actuated_drive_body_and_rotor1d_follow_the_closed_form():
    res = run("actuated_drive", 1.1, 23)
    t = res.t
    phi = t / (4 * np.pi) - np.sin(2 * np.pi * t) / (8 * np.pi**2)      # 2 phi'' = sin(2 pi t)
    w = (1 - np.cos(2 * np.pi * t)) / (4 * np.pi)
    for probe in ("phi_3d", "phi_1d"):
        np.testing.assert_allclose(res[f"{probe}.angle"], phi, atol=1e-10)
        np.testing.assert_allclose(res[f"{probe}.speed"], w, atol=1e-10)


def test_gyroscopic_effects_rotor1d_moves_as_the_spinning_cylinder():
    """MSL: the cylinder on a revolute and the fixed cylinder plus a Rotor1D of its axial
    inertia give the same motion and the same reaction on the world."""
    res = run("gyroscopic_effects", 1.0, 11)
    for a, b in [("tip1.position", "tip2.position"), ("reaction1.force", "reaction2.force"),
                 ("reaction1.torque", "reaction2.torque")]:
        np.testing.assert_allclose(res[b], res[a], atol=1e-8)
    np.testing.assert_allclose(res["rotor1D.spin.qd"], res["revolute.qd"], atol=1e-8)
    assert np.ptp(res["tip1.position"][:, 1]) > 0.1                  # it swings and precesses


def test_rolling_wheel_keeps_its_energy_and_does_not_slip():
    res = run("rolling_wheel", 1.0, 21)
    m, inertia = 2.0, np.diag([0.12, 0.06, 0.12])
    pos, v, w = (res[f"centre.{q}"] for q in ("position", "velocity", "angular_velocity"))
    angles = [res[f"wheel1.joint.angles[{i}]"] for i in range(3)]
    c, s = np.cos(angles), np.sin(angles)
    # the wheel's axis: Rz Ry Rx applied to y (MSL's angles about z, y, x)
    axis = np.stack([c[0] * s[1] * s[2] - s[0] * c[2], s[0] * s[1] * s[2] + c[0] * c[2],
                     c[1] * s[2]], axis=1)
    along = np.cross([0, 0, 1], axis)
    along /= np.linalg.norm(along, axis=1)[:, None]
    delta = 0.3 * np.cross(along, axis)
    np.testing.assert_allclose(pos[:, 2] + delta[:, 2], 0, atol=1e-10)     # it touches
    np.testing.assert_allclose(v + np.cross(w, delta), 0, atol=1e-8)      # and rolls
    spin = np.einsum("ni,ni->n", w, axis)
    w_perp = w - spin[:, None] * axis
    energy = (0.5 * m * np.sum(v**2, axis=1) + m * 9.81 * pos[:, 2]
              + 0.5 * inertia[1, 1] * spin**2 + 0.5 * inertia[0, 0] * np.sum(w_perp**2, axis=1))
    np.testing.assert_allclose(energy, energy[0], rtol=1e-9)
    # the animation draws the wheel as a disk of its diameter about its axis, on its frame
    disk, = [s for s in animation_data(res)["shapes"] if s["component"] == "wheel1.joint"]
    assert (disk["kind"], disk["length_direction"], disk["width"]) == ("cylinder", [0, 1, 0], 0.6)


def test_line_force_with_two_masses_both_halves_and_an_independent_lagrangian():
    """MSL's figure: the JointUPS half and the LineForceWithTwoMasses half move alike and cut
    the same forces at the boxes' tips and at the rods holding them (body_f_diff = rod_f_diff
    = 0: the JointUPS passes its damper's force to its frames, as MSL's); the lower half is
    also the sympy Lagrangian of scenes/line_masses.py, its cut forces MSL's equations."""
    box = 7700 * 0.7 * 0.035**2                           # MSL's BodyBox: width = length/20
    scene = Scene(pivot=(0.0, 0.3, 0.3), anchor=(0.0, -0.9, 0.3), tip=0.7, mass=box, cm=0.35,
                  izz=box * (0.7**2 + 0.035**2) / 12, m_a=1.0, m_b=1.0, L_a=0.2, L_b=0.2,
                  c=0.0, d=3.0, s0=0.0)
    res = run("line_force_with_two_masses", 1.5, 16)
    acc, kin, phi, w = solve(scene, res.t)
    for half in ("angle1", "angle2"):
        np.testing.assert_allclose(res[f"{half}.angle"], phi, atol=1e-9)
        np.testing.assert_allclose(res[f"{half}.speed"], w, atol=1e-9)
    assert np.ptp(phi) > 0.5
    np.testing.assert_allclose(res["box1_f.force"], res["box2_f.force"], atol=1e-8)
    for k in range(0, len(res.t), 5):
        f_a, f_b = msl_cut_forces(scene, acc, kin, phi[k], w[k])
        # the line's frames are wired to rod3 and to the box: their flows are the opposites
        np.testing.assert_allclose(res["rod3_f.force"][k], -f_a, atol=1e-8)
        np.testing.assert_allclose(res["box2_f.force"][k], -f_b, atol=1e-8)
    np.testing.assert_allclose(res["rod1_f.force"], res["rod3_f.force"], atol=1e-8)
    assert res.state_names == ["revolute1.q", "revolute2.q", "revolute1.qd", "revolute2.qd"]


def _circles(a, b, ra, rb, side):
    """The point ra from a and rb from b (planar, z = 0) on ``side`` of the line a -> b."""
    d = b - a
    L = np.linalg.norm(d, axis=1)[:, None]
    x = (L**2 + ra**2 - rb**2) / (2 * L)
    h = np.sqrt(ra**2 - x**2)
    e = d / L
    n = np.stack([-e[:, 1], e[:, 0], np.zeros(len(e))], axis=1)
    return a + x * e + side * h * n


def test_planar_loops_analytic_middle_joints_on_the_closed_form():
    res = run("planar_loops_analytic", 1.0, 21)
    t = res.t
    phi = 0.7 * np.sin(2 * np.pi * t)
    np.testing.assert_allclose(res["drive.angle"], phi, atol=1e-12)
    rh, rv = np.array([0.5, 0, 0]), np.array([0, 0.5, 0])
    rb = [np.array([0.1, 0.5, 0]), np.array([0.1, 0.6, 0]), np.array([0, 0.55, 0])]
    ra = [rb[0] + rh - rv, rb[1] + rh - rb[0], rb[2] + rh - rb[1]]
    a = np.stack([-np.sin(phi) * 0.5, np.cos(phi) * 0.5, 0 * phi], axis=1)   # Rz(phi) rv
    for k in range(3):
        b = np.tile((k + 1) * rh, (len(t), 1))
        start = (k + 1) * rh + rb[k]                       # assembled with zero angles
        d0, s0 = b[0] - a[0], start - a[0]
        side = np.sign(d0[0] * s0[1] - d0[1] * s0[0])
        middle = _circles(a, b, np.linalg.norm(ra[k]), np.linalg.norm(rb[k]), side)
        np.testing.assert_allclose(middle[0], start, atol=1e-12)
        np.testing.assert_allclose(res[f"middle{k + 1}.position"], middle, atol=1e-9)
        a = middle
