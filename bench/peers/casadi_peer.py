"""kinetwork's own route written by hand: Featherstone's articulated-body algorithm in CasADi SX,
compiled to C, integrated by CVODES (Adams) through ``casadi.integrator`` in one call.

What a skilled user would write instead of using kinetwork: the ABA of Featherstone's *Rigid
Body Dynamics Algorithms* (Table 7.1) on 6-D spatial vectors ([angular; linear]), the
right-hand side generated as C by CasADi, compiled with gcc (-O1, kinetwork's flags; -O2/-O3
are no faster on this straight-line code) and loaded back with ``casadi.external``, then one
``casadi.integrator`` call over the whole output grid. Joint ``i`` of the spec rotates about
``spec.axis[i]`` at the parent's ``offset`` (the ground's origin for the first); the
spring-dampers enter as the joint torque ``tau = -(k q + d qd)``; gravity is the base's
acceleration ``-g``.

Tolerances: ``atol = rtol * 1e-2``, as every peer.
"""

import pathlib
import subprocess
import tempfile

import casadi as ca
import numpy as np

NAME = "CasADi ABA+CVODES Adams (by hand)"
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
TIGHTEST = {"rtol": 1e-12}


def _skew(v):
    return ca.vertcat(ca.horzcat(0, -v[2], v[1]), ca.horzcat(v[2], 0, -v[0]),
                      ca.horzcat(-v[1], v[0], 0))


def _crm(v):
    """v x (motion cross product) as a 6x6 matrix."""
    w, u = _skew(v[:3]), _skew(v[3:])
    return ca.vertcat(ca.horzcat(w, ca.SX.zeros(3, 3)), ca.horzcat(u, w))


def _rotation(axis, q):
    """The rotation matrix of angle ``q`` about the unit ``axis`` (Rodrigues)."""
    k = _skew(ca.DM(axis))
    return ca.SX.eye(3) + ca.sin(q) * k + (1 - ca.cos(q)) * (k @ k)


def aba(spec, q, qd, tau):
    """Joint accelerations of the chain ``spec`` by the articulated-body algorithm (SX)."""
    n = spec.n
    X, S, v, c, IA, pA = [], [], [], [], [], []
    for i in range(n):
        E = _rotation(spec.axis[i], q[i]).T                 # parent coordinates -> link i
        r = np.zeros(3) if i == 0 else spec.offset[i - 1]   # joint i in the parent's frame
        X.append(ca.vertcat(ca.horzcat(E, ca.SX.zeros(3, 3)),
                            ca.horzcat(-E @ _skew(ca.DM(r)), E)))
        S.append(ca.DM(np.concatenate([spec.axis[i], np.zeros(3)])))
        vJ = S[i] * qd[i]
        v.append(vJ if i == 0 else X[i] @ v[i - 1] + vJ)
        c.append(_crm(v[i]) @ vJ)
        m, h = spec.mass[i], _skew(ca.DM(spec.r_cm[i]))
        inertia = ca.DM(spec.inertia[i]) + m * (h @ h.T)
        IA.append(ca.SX(ca.vertcat(ca.horzcat(inertia, m * h), ca.horzcat(m * h.T,
                                                                         m * ca.DM.eye(3)))))
        pA.append(-_crm(v[i]).T @ (IA[i] @ v[i]))          # v x* (I v)
    U, D, u = [None] * n, [None] * n, [None] * n
    for i in reversed(range(n)):
        U[i] = IA[i] @ S[i]
        D[i] = S[i].T @ U[i]
        u[i] = tau[i] - S[i].T @ pA[i]
        if i > 0:
            Ia = IA[i] - U[i] @ U[i].T / D[i]
            pa = pA[i] + Ia @ c[i] + U[i] * u[i] / D[i]
            IA[i - 1] = IA[i - 1] + X[i].T @ Ia @ X[i]
            pA[i - 1] = pA[i - 1] + X[i].T @ pa
    a_parent = ca.DM(np.concatenate([np.zeros(3), -np.asarray(spec.gravity, float)]))
    qdd = []
    for i in range(n):
        a = X[i] @ a_parent + c[i]
        qdd.append((u[i] - U[i].T @ a) / D[i])
        a_parent = a + S[i] * qdd[i]
    return ca.vertcat(*qdd)


class Built:
    """The compiled right-hand side of one chain, its initial state and the integrators made
    so far (one per output grid and tolerance, as a user would keep them)."""

    def __init__(self, rhs, x0, n, folder):
        self.rhs, self.x0, self.n, self.folder = rhs, x0, n, folder
        self.integrators = {}


def build(spec):
    """The ABA right-hand side of ``spec`` compiled to C and loaded back."""
    n = spec.n
    x = ca.SX.sym("x", 2 * n)
    q, qd = x[:n], x[n:]
    tau = -(ca.DM(spec.stiffness) * q + ca.DM(spec.damping) * qd)
    f = ca.Function("chain_rhs", [x], [ca.vertcat(qd, aba(spec, q, qd, tau))])
    folder = tempfile.mkdtemp(prefix="casadi-peer-")
    source = pathlib.Path(folder) / "chain_rhs.c"
    gen = ca.CodeGenerator(source.name, {"with_header": False})
    gen.add(f)
    source.write_text(gen.dump())
    lib = source.with_suffix(".so")
    subprocess.run(["gcc", "-O1", "-fPIC", "-shared", "-o", str(lib), str(source), "-lm"],
                   check=True)
    x0 = np.concatenate([spec.q0, spec.qd0]).astype(float)
    # CVODES builds a Jacobian function even for functional iteration (never called):
    # finite differences keep it from asking for derivative code
    rhs = ca.external("chain_rhs", str(lib), {"enable_fd": True})
    return Built(rhs, x0, n, folder)


def integrator(built, t, rtol, atol):
    """CVODES Adams with functional iteration over the output grid ``t`` (kept per grid)."""
    key = (t[0], t[-1], len(t), rtol, atol)
    if key not in built.integrators:
        x = ca.MX.sym("x", 2 * built.n)
        opts = {"linear_multistep_method": "adams", "nonlinear_solver_iteration": "functional",
                "reltol": rtol, "abstol": atol, "max_num_steps": 100000}
        built.integrators[key] = ca.integrator("I", "cvodes", {"x": x, "ode": built.rhs(x)},
                                               float(t[0]), list(map(float, t[1:])), opts)
    return built.integrators[key]


def trajectory(built, t, rtol=1e-8, atol=None):
    """Joint angles and rates, each (len(t), N), from ``spec.q0``, ``spec.qd0`` at ``t[0]``.

    ``atol`` defaults to ``rtol * 1e-2``. Raises RuntimeError if the integration fails.
    """
    t = np.asarray(t, dtype=float)
    out = integrator(built, t, rtol, rtol * 1e-2 if atol is None else atol)(x0=built.x0)
    X = np.vstack([built.x0, np.asarray(out["xf"]).T])
    return X[:, :built.n], X[:, built.n:]


def run(built, t, **options):
    """Joint angles (len(t), N) from ``spec.q0``, ``spec.qd0`` at ``t[0]``; see ``trajectory``."""
    return trajectory(built, t, **options)[0]


def variants():
    """CVODES Adams at rtol 1e-3 .. 1e-12."""
    return [{"rtol": r} for r in RTOLS]
