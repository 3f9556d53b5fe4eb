"""MuJoCo: the chain as MJCF, stepped at a fixed time step with ``mj_step``.

The MJCF is generated from the spec: nested bodies, body ``i`` at its parent's ``offset`` (the
world origin for the first), with no rotation, so that the hinge ``axis`` given in the parent's
frame is also the axis in the body's own frame; ``<inertial>`` with ``pos = r_cm`` and the
inertia about the centre of mass in body axes (``diaginertia`` if diagonal, else
``fullinertia``, which MuJoCo turns into principal axes); the joint spring-damper as the hinge's
``stiffness``/``damping`` about ``springref = 0``. Everything else that MuJoCo would add is
switched off: contacts and other constraints (no geoms, no limits), armature, friction loss.

MuJoCo refuses zero inertia ("mass and inertia of moving bodies must be larger than
mjMINVAL"; ``diaginertia`` accepts 1e-15, ``fullinertia``, which goes through an
eigendecomposition, only 1e-14), so point masses get an isotropic inertia of
``POINT_INERTIA`` = 1e-15 kg m^2. On the seed scene this changes the angles by 1e-15 rad
over 10 s (``check.py`` measures it with pinocchio).

``run`` steps at ``timestep`` and records ``qpos`` on the output grid, whose spacing must be a
whole number of steps.
"""

import numpy as np
import mujoco

NAME = "MuJoCo"
POINT_INERTIA = mujoco.mjMINVAL     # moment of a point mass: the smallest accepted, kg m^2
INTEGRATORS = ("RK4", "implicit", "implicitfast", "Euler")
#: steps [s]: divisors of the 0.01 s output spacing
TIMESTEPS = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5)
TIGHTEST = {"integrator": "RK4", "timestep": 1e-4}
#: MuJoCo's warnings for a state gone non-finite or huge, after which it resets the state
DIVERGED = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
            mujoco.mjtWarning.mjWARN_BADQACC)


def _vec(v):
    return " ".join(repr(float(x)) for x in v)


def mjcf(spec):
    """The MJCF text of ``spec`` (with MuJoCo's default integrator and step)."""
    bodies, close = [], []
    at = np.zeros(3)
    for i in range(spec.n):
        I = np.asarray(spec.inertia[i], dtype=float)
        if not I.any():
            I = POINT_INERTIA * np.eye(3)
        if np.count_nonzero(I - np.diag(np.diag(I))):
            inertia = f'fullinertia="{_vec((*np.diag(I), I[0, 1], I[0, 2], I[1, 2]))}"'
        else:       # as given; fullinertia would go through an eigendecomposition
            inertia = f'diaginertia="{_vec(np.diag(I))}"'
        indent = "  " * (i + 2)
        bodies.append(
            f'{indent}<body name="b{i}" pos="{_vec(at)}">\n'
            f'{indent}  <joint name="j{i}" type="hinge" pos="0 0 0" axis="{_vec(spec.axis[i])}"'
            f' stiffness="{float(spec.stiffness[i])!r}" springref="0"'
            f' damping="{float(spec.damping[i])!r}" armature="0" frictionloss="0"'
            f' limited="false"/>\n'
            f'{indent}  <inertial pos="{_vec(spec.r_cm[i])}" mass="{float(spec.mass[i])!r}"'
            f' {inertia}/>')
        close.append(f"{indent}</body>")
        at = spec.offset[i]
    return "\n".join([
        '<mujoco model="chain">',
        '  <compiler angle="radian" inertiafromgeom="false" balanceinertia="false"/>',
        f'  <option gravity="{_vec(spec.gravity)}">',
        '    <flag contact="disable" constraint="disable"/>',
        '  </option>',
        '  <worldbody>',
        *bodies, *reversed(close),
        '  </worldbody>',
        '</mujoco>']) + "\n"


class Built:
    """The compiled ``MjModel``, its ``MjData`` and the initial state."""

    def __init__(self, spec, model):
        self.model = model
        self.data = mujoco.MjData(model)
        self.q0 = np.asarray(spec.q0, dtype=float)
        self.qd0 = np.asarray(spec.qd0, dtype=float)
        self.n = spec.n


def build(spec):
    """Compile the MJCF of ``spec`` (integrator and step are set per run)."""
    return Built(spec, mujoco.MjModel.from_xml_string(mjcf(spec)))


def run(built, t, **options):
    """Joint angles (len(t), N) from ``spec.q0``, ``spec.qd0`` at ``t[0]``; see ``trajectory``."""
    return trajectory(built, t, **options)[0]


def trajectory(built, t, integrator="RK4", timestep=1e-3):
    """Joint angles and rates, each (len(t), N), at ``t`` (evenly spaced, a whole number of
    steps apart). Raises RuntimeError if the state diverged: MuJoCo then resets it to q = 0
    and goes on, so the rest of the trajectory would be meaningless. Past its stability limit
    RK4 can also settle on a spurious finite solution with no warning at all (stiff1e4 at
    h = 1e-4 s: 14 rad off); only the error against a reference shows that."""
    m, d = built.model, built.data
    t = np.asarray(t, dtype=float)
    spacing = (t[-1] - t[0]) / (len(t) - 1)
    k = int(round(spacing / timestep))
    uneven = np.ptp(np.diff(t)) > 1e-9 * spacing
    if k < 1 or abs(k * timestep - spacing) > 1e-9 * spacing or uneven:
        raise ValueError(f"{NAME}: output spacing {spacing} s is not a whole number of "
                         f"steps of {timestep} s on an even grid")
    m.opt.timestep = timestep
    m.opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    mujoco.mj_resetData(m, d)
    d.time = t[0]
    d.qpos[:] = built.q0
    d.qvel[:] = built.qd0
    q, qd = np.empty((len(t), built.n)), np.empty((len(t), built.n))
    q[0], qd[0] = d.qpos, d.qvel
    step = mujoco.mj_step
    for j in range(1, len(t)):
        step(m, d, k)
        q[j], qd[j] = d.qpos, d.qvel
    bad = [w for w in DIVERGED if d.warning[w].number]
    if bad:
        raise RuntimeError(f"{NAME} {integrator} h={timestep}: unstable; MuJoCo reset the state "
                           f"({mujoco.mju_warningText(bad[0], d.warning[bad[0]].lastinfo)})")
    return q, qd


def energy(built, q, qd):
    """Kinetic + gravitational potential + spring energy (MuJoCo's ``mj_energyPos/Vel``)."""
    m, d = built.model, built.data
    result = []
    for qi, vi in zip(np.atleast_2d(q), np.atleast_2d(qd)):
        d.qpos[:], d.qvel[:] = qi, vi
        mujoco.mj_forward(m, d)
        mujoco.mj_energyPos(m, d)
        mujoco.mj_energyVel(m, d)
        result.append(d.energy[0] + d.energy[1])
    return np.array(result)


def variants():
    """Each integrator at each step from 1e-2 to 1e-5 s; RK4 only down to 5e-5 s, where it
    has long reached round-off (1e-13 rad on the seed from 2e-4 s on)."""
    return [{"integrator": i, "timestep": h} for i in INTEGRATORS for h in TIMESTEPS
            if i != "RK4" or h >= 5e-5]
