"""Independent references for kinetwork's closed-loop tests (issue 4): a planar four-bar linkage
and a planar slider-crank, each reduced to one degree of freedom, the crank angle ``theta``.

Nothing here uses kinetwork. The closures are closed form (atan2 / law of cosines); the
equations of motion come from the Lagrangian of the reduced system, derived once with sympy
(exact derivatives, no finite differences) and turned into numpy functions with
``sympy.lambdify``. The derivation is cached (``functools.lru_cache``): importing this module
is cheap, the first call pays for the sympy work.

Conventions (both mechanisms)
-----------------------------
* Planar, in the x-y plane; gravity ``g`` (default 9.81) along -y; SI units, radians.
* Every angle is absolute, measured counter-clockwise from the +x axis.
* A link is a rigid body with its centre of mass at its midpoint and moment of inertia ``J``
  about its centre of mass (about z); by default ``J = m L**2 / 12`` (slender rod).
* Equation of motion (Lagrange, one coordinate)::

      m(theta) theta'' + 0.5 m'(theta) theta'**2 + dV/dtheta = Q

  with generalised mass ``m(theta) = sum_i m_i |d r_ci/d theta|**2 + J_i (d angle_i/d theta)**2``,
  potential ``V = g sum_i m_i y_ci + 0.5 k (theta - theta_rest)**2 [+ 0.5 ks (x_B - x_rest)**2]``
  (the crank's torsional spring, and for the slider-crank the slider's linear spring, are
  counted as potential energy), and ``Q = tau - cdamp theta'`` (crank damper and constant
  crank drive torque; both default 0, as do ``k`` and ``ks``).
* ``energy`` is the mechanical energy ``T + V`` (kinetic + gravity + springs); it is conserved
  when ``cdamp = tau = 0`` and decreases at the rate ``cdamp theta'**2`` when ``tau = 0``.

Four-bar
--------
Ground pivots A = (0, 0) and D = (d, 0). Crank AB, length ``a``, angle ``theta``:
B = A + a (cos theta, sin theta). Coupler BC, length ``b``, angle ``phi``:
C = B + b (cos phi, sin phi). Rocker DC, length ``c``, angle ``psi``:
C = D + c (cos psi, sin psi). Masses ``m1, m2, m3`` and inertias ``J1, J2, J3`` of crank,
coupler and rocker. Defaults d=1.0, a=0.3, b=1.0, c=0.8, m1=1.0, m2=2.0, m3=1.5 (a Grashof
crank-rocker: the crank turns fully, the branch never changes).

Assembly branch: with f = |D - B| and alpha = arccos((b**2 + f**2 - c**2) / (2 b f)) in [0, pi]
the angle at B between BD and BC, ``phi = atan2(D - B) + branch * alpha``.

* ``branch=+1`` (default): C lies on the LEFT of the directed line from B to D (the triangle
  B, D, C is counter-clockwise), the "open / elbow-up" assembly: C is above the ground line for
  theta = pi/2, and for the default geometry C = (0.998.., 0.800..) at theta = 1.0.
* ``branch=-1``: C on the right of B -> D, the mirror ("crossed / elbow-down") assembly.

``phi`` and ``psi`` are returned in (-pi, pi]; ``fourbar_simulate`` unwraps them in time.

Slider-crank
------------
Crank OA from the ground pivot O = (0, 0), length ``r``, angle ``theta``:
A = r (cos theta, sin theta). Connecting rod AB, length ``l``; slider B on the line y = e
(offset ``e``), on the branch with the slider to the right of A:
x_B = r cos theta + sqrt(l**2 - (r sin theta - e)**2). Rod angle ``beta`` = absolute angle of
B - A, i.e. beta = arcsin((e - r sin theta) / l) in (-pi/2, pi/2). Crank: m1, J1; rod: m2, J2;
slider: point mass m3 at B (moves in x only; its height is constant). Defaults r=0.2, l=0.6,
e=0.0, m1=1.0, m2=0.5, m3=2.0. Optional slider spring force -ks (x_B - x_rest) (default
ks=0, x_rest=l).
"""

import functools
import math

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

FOURBAR = {"d": 1.0, "a": 0.3, "b": 1.0, "c": 0.8, "m1": 1.0, "m2": 2.0, "m3": 1.5,
           "J1": None, "J2": None, "J3": None, "g": 9.81,
           "k": 0.0, "cdamp": 0.0, "theta_rest": 0.0, "tau": 0.0, "branch": 1}

SLIDER_CRANK = {"r": 0.2, "l": 0.6, "e": 0.0, "m1": 1.0, "m2": 0.5, "m3": 2.0,
                "J1": None, "J2": None, "g": 9.81,
                "k": 0.0, "cdamp": 0.0, "theta_rest": 0.0, "tau": 0.0,
                "ks": 0.0, "x_rest": None}



def _merge(defaults, overrides):
    unknown = set(overrides) - set(defaults)
    if unknown:
        raise TypeError(f"unknown parameter(s): {sorted(unknown)}")
    return {**defaults, **overrides}


def fourbar_params(**overrides):
    """The full four-bar parameter set: defaults, ``overrides``, J_i = m_i L_i^2/12 if None."""
    p = _merge(FOURBAR, overrides)
    for J, m, L in (("J1", "m1", "a"), ("J2", "m2", "b"), ("J3", "m3", "c")):
        if p[J] is None:
            p[J] = p[m] * p[L] ** 2 / 12
    if p["branch"] not in (1, -1):
        raise ValueError("branch must be +1 or -1")
    return p


def slider_crank_params(**overrides):
    """The full slider-crank parameter set (J_i = m_i L_i^2/12 and x_rest = l if None)."""
    p = _merge(SLIDER_CRANK, overrides)
    for J, m, L in (("J1", "m1", "r"), ("J2", "m2", "l")):
        if p[J] is None:
            p[J] = p[m] * p[L] ** 2 / 12
    if p["x_rest"] is None:
        p["x_rest"] = p["l"]
    if p["l"] <= p["r"] + abs(p["e"]):
        raise ValueError("need l > r + |e| for the crank to turn fully")
    return p


# ----------------------------------------------------------------------------------------------
# Four-bar
# ----------------------------------------------------------------------------------------------

_FB_ARGS = ("a", "b", "c", "d", "m1", "m2", "m3", "J1", "J2", "J3", "g")


@functools.lru_cache(maxsize=2)
def _fourbar_functions(module="numpy"):
    """Exact kinematic and dynamic functions of (theta, phi, psi, *_FB_ARGS), on arrays
    (``module="numpy"``) or on floats (``"math"``: the integrator's right-hand side, 4x
    faster on one point).

    theta, phi, psi are treated as independent symbols tied by the loop closure
    a e(theta) + b e(phi) - c e(psi) - (d, 0) = 0. Its theta-derivative is linear in
    phi' and psi', which gives them exactly; any further theta-derivative is the total
    derivative D f = df/dtheta + phi' df/dphi + psi' df/dpsi.
    """
    th, ph, ps = sp.symbols("theta phi psi", real=True)
    a, b, c, d, m1, m2, m3, J1, J2, J3, g = sp.symbols(_FB_ARGS, positive=True)
    php, psp = sp.symbols("phi_p psi_p", real=True)

    def e(angle):
        return sp.Matrix([sp.cos(angle), sp.sin(angle)])

    loop = a * e(th) + b * e(ph) - c * e(ps) - sp.Matrix([d, 0])
    dloop = loop.diff(th) + php * loop.diff(ph) + psp * loop.diff(ps)
    sol = sp.solve(list(dloop), [php, psp], dict=True)[0]
    phi_p = sp.simplify(sol[php])   # a sin(psi - theta) / (b sin(phi - psi))
    psi_p = sp.simplify(sol[psp])   # a sin(phi - theta) / (c sin(phi - psi))

    def D(f):
        return sp.diff(f, th) + phi_p * sp.diff(f, ph) + psi_p * sp.diff(f, ps)

    # centres of mass (midpoints) of crank, coupler, rocker
    r1 = a / 2 * e(th)
    r2 = a * e(th) + b / 2 * e(ph)
    r3 = sp.Matrix([d, 0]) + c / 2 * e(ps)
    masses = (m1, m2, m3)
    jac = [r.applyfunc(D) for r in (r1, r2, r3)]
    mass = (sum(m * (j.T * j)[0, 0] for m, j in zip(masses, jac))
            + J1 + J2 * phi_p ** 2 + J3 * psi_p ** 2)
    Vg = g * sum(m * r[1] for m, r in zip(masses, (r1, r2, r3)))
    exprs = {
        "phi_p": phi_p, "psi_p": psi_p, "phi_pp": D(phi_p), "psi_pp": D(psi_p),
        "mass": mass, "mass_p": D(mass),
        "Vg": Vg, "Vg_p": D(Vg), "Vg_pp": D(D(Vg)),
    }
    args = (th, ph, ps) + (a, b, c, d, m1, m2, m3, J1, J2, J3, g)
    return {name: sp.lambdify(args, ex, modules=module, cse=True) for name, ex in exprs.items()}


def fourbar_closure(theta, branch=1, a=FOURBAR["a"], b=FOURBAR["b"], c=FOURBAR["c"],
                    d=FOURBAR["d"], **_ignored):
    """(phi, psi) of coupler and rocker for crank angle(s) ``theta``, in (-pi, pi].

    ``branch=+1``: C on the left of the directed line B -> D (default, C above the ground);
    ``branch=-1``: the mirror assembly. Raises ValueError where the loop cannot close.
    """
    theta = np.asarray(theta, dtype=float)
    Bx, By = a * np.cos(theta), a * np.sin(theta)
    wx, wy = d - Bx, -By                          # B -> D
    f = np.hypot(wx, wy)
    cos_alpha = (b ** 2 + f ** 2 - c ** 2) / (2 * b * f)
    if np.any(np.abs(cos_alpha) > 1):
        raise ValueError("four-bar cannot be assembled at this crank angle")
    phi = np.arctan2(wy, wx) + branch * np.arccos(cos_alpha)
    Cx, Cy = Bx + b * np.cos(phi), By + b * np.sin(phi)
    psi = np.arctan2(Cy, Cx - d)
    phi = np.angle(np.exp(1j * phi))              # wrap to (-pi, pi]
    return phi, psi


def _closure_of_one(theta, branch, a, b, c, d):
    """fourbar_closure of one crank angle, on floats (the same formulas)."""
    Bx, By = a * math.cos(theta), a * math.sin(theta)
    wx, wy = d - Bx, -By
    f = math.hypot(wx, wy)
    cos_alpha = (b ** 2 + f ** 2 - c ** 2) / (2 * b * f)
    if abs(cos_alpha) > 1:
        raise ValueError("four-bar cannot be assembled at this crank angle")
    phi = math.atan2(wy, wx) + branch * math.acos(cos_alpha)
    psi = math.atan2(By + b * math.sin(phi), Bx + b * math.cos(phi) - d)
    return math.remainder(phi, 2 * math.pi), psi


def fourbar_points(theta, branch=1, a=FOURBAR["a"], b=FOURBAR["b"], c=FOURBAR["c"],
                   d=FOURBAR["d"], **_ignored):
    """Joint positions (B, C), each of shape theta.shape + (2,), from the closure."""
    theta = np.asarray(theta, dtype=float)
    phi, _ = fourbar_closure(theta, branch, a=a, b=b, c=c, d=d)
    B = np.stack([a * np.cos(theta), a * np.sin(theta)], axis=-1)
    C = B + b * np.stack([np.cos(phi), np.sin(phi)], axis=-1)
    return B, C


def fourbar_kinematics(theta, **params):
    """dict of phi, psi and their exact first/second theta-derivatives (phi_p, psi_p,
    phi_pp, psi_pp), with the generalised mass ``mass`` = m(theta), ``mass_p`` = m'(theta),
    and the gravity potential ``Vg`` with ``Vg_p``, ``Vg_pp``."""
    p = fourbar_params(**params)
    theta = np.asarray(theta, dtype=float)
    phi, psi = fourbar_closure(theta, **p)
    fns = _fourbar_functions()
    args = [p[name] for name in _FB_ARGS]
    out = {"phi": phi, "psi": psi}
    for name, fn in fns.items():
        out[name] = np.broadcast_to(fn(theta, phi, psi, *args), theta.shape).astype(float)[()]
    return out


def _fourbar_accel(theta, thetad, p, kin):
    Q = p["tau"] - p["cdamp"] * thetad
    dV = kin["Vg_p"] + p["k"] * (theta - p["theta_rest"])
    return (Q - 0.5 * kin["mass_p"] * thetad ** 2 - dV) / kin["mass"]


def fourbar_rhs(t, y, **params):
    """d/dt (theta, theta') of the four-bar: y = (theta, theta')."""
    p = fourbar_params(**params)
    theta, thetad = y
    kin = fourbar_kinematics(theta, **p)
    return np.array([thetad, _fourbar_accel(theta, thetad, p, kin)])


def fourbar_energy(theta, thetad, **params):
    """Mechanical energy T + V (gravity with y = 0 on the ground line, crank spring)."""
    p = fourbar_params(**params)
    theta = np.asarray(theta, dtype=float)
    kin = fourbar_kinematics(theta, **p)
    return (0.5 * kin["mass"] * np.asarray(thetad) ** 2 + kin["Vg"]
            + 0.5 * p["k"] * (theta - p["theta_rest"]) ** 2)


def fourbar_simulate(theta0, thetad0, t_eval, rtol=1e-12, atol=1e-12, **params):
    """Integrate the four-bar from (theta0, theta'0) and sample it on ``t_eval`` (DOP853).

    Returns a dict of arrays: t, theta, thetad, thetadd, phi, psi (unwrapped in time),
    phid, psid, phidd, psidd, B, C (shape (n, 2)) and energy.
    """
    p = fourbar_params(**params)
    fns = _fourbar_functions("math")
    args = [p[name] for name in _FB_ARGS]
    mass, mass_p, Vg_p = fns["mass"], fns["mass_p"], fns["Vg_p"]
    branch, geometry = p["branch"], {key: p[key] for key in "abcd"}

    def rhs(_, y):                                 # scalar fast path of fourbar_rhs
        theta, thetad = float(y[0]), float(y[1])
        phi, psi = _closure_of_one(theta, branch, **geometry)
        kin = {"mass": mass(theta, phi, psi, *args), "mass_p": mass_p(theta, phi, psi, *args),
               "Vg_p": Vg_p(theta, phi, psi, *args)}
        return [thetad, _fourbar_accel(theta, thetad, p, kin)]

    t_eval = np.asarray(t_eval, dtype=float)
    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), [theta0, thetad0], t_eval=t_eval,
                    method="DOP853", rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(sol.message)
    theta, thetad = sol.y
    kin = fourbar_kinematics(theta, **p)
    thetadd = _fourbar_accel(theta, thetad, p, kin)
    B, C = fourbar_points(theta, **p)
    return {
        "t": sol.t, "theta": theta, "thetad": thetad, "thetadd": thetadd,
        "phi": np.unwrap(kin["phi"]), "psi": np.unwrap(kin["psi"]),
        "phid": kin["phi_p"] * thetad, "psid": kin["psi_p"] * thetad,
        "phidd": kin["phi_pp"] * thetad ** 2 + kin["phi_p"] * thetadd,
        "psidd": kin["psi_pp"] * thetad ** 2 + kin["psi_p"] * thetadd,
        "B": B, "C": C,
        "energy": fourbar_energy(theta, thetad, **p),
    }


# ----------------------------------------------------------------------------------------------
# Slider-crank
# ----------------------------------------------------------------------------------------------

_SC_ARGS = ("r", "l", "e", "m1", "m2", "m3", "J1", "J2", "g")


@functools.lru_cache(maxsize=1)
def _slider_crank_functions():
    """Exact functions of (theta, *_SC_ARGS): here the closure is explicit in theta, so
    plain sympy differentiation gives every derivative."""
    th = sp.symbols("theta", real=True)
    r, l, m1, m2, m3, J1, J2, g = sp.symbols("r l m1 m2 m3 J1 J2 g", positive=True)
    e = sp.symbols("e", real=True)

    A = sp.Matrix([r * sp.cos(th), r * sp.sin(th)])
    xB = r * sp.cos(th) + sp.sqrt(l ** 2 - (r * sp.sin(th) - e) ** 2)
    B = sp.Matrix([xB, e])
    beta = sp.asin((e - r * sp.sin(th)) / l)     # B - A = l (cos beta, sin beta), cos beta > 0
    r1, r2 = A / 2, (A + B) / 2                  # crank and rod centres of mass
    j1, j2 = r1.diff(th), r2.diff(th)
    xB_p, beta_p = sp.diff(xB, th), sp.diff(beta, th)
    mass = (m1 * (j1.T * j1)[0, 0] + m2 * (j2.T * j2)[0, 0] + m3 * xB_p ** 2
            + J1 + J2 * beta_p ** 2)
    Vg = g * (m1 * r1[1] + m2 * r2[1] + m3 * e)
    exprs = {
        "x": xB, "x_p": xB_p, "x_pp": sp.diff(xB_p, th),
        "beta": beta, "beta_p": beta_p, "beta_pp": sp.diff(beta_p, th),
        "mass": mass, "mass_p": sp.diff(mass, th),
        "Vg": Vg, "Vg_p": sp.diff(Vg, th), "Vg_pp": sp.diff(Vg, th, 2),
    }
    args = (th, r, l, e, m1, m2, m3, J1, J2, g)
    return {name: sp.lambdify(args, ex, modules="numpy", cse=True) for name, ex in exprs.items()}


def slider_crank_closure(theta, r=SLIDER_CRANK["r"], l=SLIDER_CRANK["l"], e=SLIDER_CRANK["e"],
                         **_ignored):
    """(x_B, beta): slider position and rod angle for crank angle(s) ``theta``."""
    theta = np.asarray(theta, dtype=float)
    s = r * np.sin(theta) - e
    x = r * np.cos(theta) + np.sqrt(l ** 2 - s ** 2)
    beta = np.arctan2(-s, x - r * np.cos(theta))
    return x, beta


def slider_crank_points(theta, r=SLIDER_CRANK["r"], l=SLIDER_CRANK["l"], e=SLIDER_CRANK["e"],
                        **_ignored):
    """Joint positions (A, B), each of shape theta.shape + (2,)."""
    theta = np.asarray(theta, dtype=float)
    x, _ = slider_crank_closure(theta, r=r, l=l, e=e)
    A = np.stack([r * np.cos(theta), r * np.sin(theta)], axis=-1)
    B = np.stack([x, np.full_like(x, e)], axis=-1)
    return A, B


def slider_crank_kinematics(theta, **params):
    """dict of x, beta, their exact theta-derivatives (x_p, x_pp, beta_p, beta_pp), the
    generalised mass (mass, mass_p) and the gravity potential (Vg, Vg_p, Vg_pp)."""
    p = slider_crank_params(**params)
    theta = np.asarray(theta, dtype=float)
    args = [p[name] for name in _SC_ARGS]
    return {name: np.broadcast_to(fn(theta, *args), theta.shape).astype(float)[()]
            for name, fn in _slider_crank_functions().items()}


def _slider_crank_accel(theta, thetad, p, kin):
    Q = p["tau"] - p["cdamp"] * thetad
    dV = (kin["Vg_p"] + p["k"] * (theta - p["theta_rest"])
          + p["ks"] * (kin["x"] - p["x_rest"]) * kin["x_p"])
    return (Q - 0.5 * kin["mass_p"] * thetad ** 2 - dV) / kin["mass"]


def slider_crank_rhs(t, y, **params):
    """d/dt (theta, theta') of the slider-crank: y = (theta, theta')."""
    p = slider_crank_params(**params)
    theta, thetad = y
    kin = slider_crank_kinematics(theta, **p)
    return np.array([thetad, _slider_crank_accel(theta, thetad, p, kin)])


def slider_crank_energy(theta, thetad, **params):
    """Mechanical energy T + V (gravity with y = 0 on the x axis, crank and slider springs)."""
    p = slider_crank_params(**params)
    theta = np.asarray(theta, dtype=float)
    kin = slider_crank_kinematics(theta, **p)
    return (0.5 * kin["mass"] * np.asarray(thetad) ** 2 + kin["Vg"]
            + 0.5 * p["k"] * (theta - p["theta_rest"]) ** 2
            + 0.5 * p["ks"] * (kin["x"] - p["x_rest"]) ** 2)


def slider_crank_simulate(theta0, thetad0, t_eval, rtol=1e-12, atol=1e-12, **params):
    """Integrate the slider-crank from (theta0, theta'0) and sample it on ``t_eval`` (DOP853).

    Returns a dict of arrays: t, theta, thetad, thetadd, x, xd, xdd, beta, betad, betadd,
    A, B (shape (n, 2)) and energy.
    """
    p = slider_crank_params(**params)
    fns = _slider_crank_functions()
    args = [p[name] for name in _SC_ARGS]
    names = ("x", "x_p", "mass", "mass_p", "Vg_p")

    def rhs(_, y):                                 # scalar fast path of slider_crank_rhs
        theta, thetad = y
        kin = {name: fns[name](theta, *args) for name in names}
        return [thetad, _slider_crank_accel(theta, thetad, p, kin)]

    t_eval = np.asarray(t_eval, dtype=float)
    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), [theta0, thetad0], t_eval=t_eval,
                    method="DOP853", rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(sol.message)
    theta, thetad = sol.y
    kin = slider_crank_kinematics(theta, **p)
    thetadd = _slider_crank_accel(theta, thetad, p, kin)
    A, B = slider_crank_points(theta, **p)
    return {
        "t": sol.t, "theta": theta, "thetad": thetad, "thetadd": thetadd,
        "x": kin["x"], "xd": kin["x_p"] * thetad,
        "xdd": kin["x_pp"] * thetad ** 2 + kin["x_p"] * thetadd,
        "beta": kin["beta"], "betad": kin["beta_p"] * thetad,
        "betadd": kin["beta_pp"] * thetad ** 2 + kin["beta_p"] * thetadd,
        "A": A, "B": B,
        "energy": slider_crank_energy(theta, thetad, **p),
    }
