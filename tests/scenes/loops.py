"""The scenes of issue 4 (loops, free bodies, line forces) as kinetwork models.

Their geometry is that of ``reference_loops`` (the independent closed-form references), so
the tests and the loop study compare like with like. ``python tests/scenes/loops.py`` writes
the example files ``models/fourbar.json`` and the others from these builders.

fourbar          crank-rocker: ground link d = 1, crank a = 0.3, coupler b = 1, rocker c = 0.8
                 (uniform rods, masses 1, 2, 1.5 kg), released at crank angle theta0
slider_crank     crank r = 0.2, rod l = 0.6, slider 2 kg on the x axis
spatial_fourbar  an RSUR spatial four-bar: crank about z, rocker about x, the coupler on a
                 Universal joint at the crank and a (cut) Spherical joint at the rocker
dzhanibekov      a free rigid body spinning about its intermediate axis (no gravity)
spring_pendulum  a point mass on a revolute + prismatic pair, held by a multibody Spring
fourbar_chain    N four-bars, each hanging from the rocker tip of the one before: N degrees
                 of freedom, N loops (how the equations grow)
"""

import json
import pathlib

import numpy as np

import kinetwork as kn

ROOT = pathlib.Path(__file__).resolve().parents[2]
mb = kn.multibody
G = 9.81


def _rod(model, name, frame, length_expr, mass, length, along=(1, 0, 0)):
    """A uniform rod from ``frame`` along ``along`` (scaled by ``length_expr``): a
    FixedTranslation and a RigidBody at its midpoint; returns the far frame."""
    r = [f"{length_expr}*{a}" if a else 0 for a in along]
    rc = [f"{length_expr}/2*{a}" if a else 0 for a in along]
    model.add(mb.FixedTranslation(name, r=r))
    inertia = mass * length ** 2 / 12
    diag = [inertia if not a else 0.0 for a in along]
    model.add(mb.RigidBody(f"{name}_mass", mass=mass, r_cm=rc, inertia=diag))
    model.connect(frame, f"{name}.frame_a")
    model.connect(frame, f"{name}_mass.frame_a")
    return f"{name}.frame_b"


def fourbar(theta0=1.0, thetad0=0.0, a=0.3, b=1.0, c=0.8, d=1.0, masses=(1.0, 2.0, 1.5),
            g=G, probes=True, guesses=None):
    """The planar four-bar of ``reference_loops.fourbar_*``: joint A at the origin (crank
    angle = A.q, absolute), B between crank and coupler (B.q = phi - theta), D at (d, 0)
    (D.q = psi), C closes the loop between coupler and rocker (cut)."""
    m = kn.Model("fourbar", parameters={"a": a, "b": b, "c": c, "d": d, "g": g},
                 description="A planar crank-rocker four-bar (Grashof) released under gravity; "
                             "the loop is closed by joint C, cut automatically. One degree of "
                             "freedom (crank angle and speed); the other joint angles are "
                             "projected onto the closure in every evaluation.",
                 simulation={"t_end": 10.0, "n_points": 1001, "method": "auto",
                             "rtol": 1e-12, "atol": 1e-12})
    guesses = guesses or fourbar_guesses(theta0, a, b, c, d)
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Revolute("A", q0=theta0, qd0=thetad0))
    m.connect("ground.frame", "A.frame_a")
    tip = _rod(m, "crank", "A.frame_b", "a", masses[0], a)
    m.add(mb.Revolute("B", q0_guess=guesses[0]))
    m.connect(tip, "B.frame_a")
    coupler_tip = _rod(m, "coupler", "B.frame_b", "b", masses[1], b)
    m.add(mb.FixedTranslation("base", r=["d", 0, 0]))
    m.connect("ground.frame", "base.frame_a")
    m.add(mb.Revolute("D", q0_guess=guesses[1]))
    m.connect("base.frame_b", "D.frame_a")
    rocker_tip = _rod(m, "rocker", "D.frame_b", "c", masses[2], c)
    m.add(mb.Revolute("C", q0_guess=guesses[2]))
    m.connect(coupler_tip, "C.frame_a")
    m.connect("C.frame_b", rocker_tip)
    if probes:
        m.add(kn.Probe("crank_probe", quantities=["angle", "speed", "acceleration"]))
        m.add(kn.Probe("rocker_probe", quantities=["angle", "speed"]))
        m.add(kn.Probe("coupler_point", quantities=["position"]))
        m.add(kn.Probe("pivot_D", quantities=["force"]))
        m.connect("crank_probe.port", "A.axis")
        m.connect("rocker_probe.port", "D.axis")
        m.connect("coupler_point.port", coupler_tip)
        m.connect("pivot_D.port", "D.frame_a")
    return m


def slider_crank(theta0=0.5, thetad0=3.0, r=0.2, l=0.6, masses=(1.0, 0.5, 2.0), g=G,
                 probes=True):
    """The slider-crank of ``reference_loops.slider_crank_*``: crank joint O at the origin
    (O.q = theta), rod joint A (A.q = beta - theta), slider Prismatic along x from the
    ground (slider.q = x_B), joint B closes the loop between rod and slider."""
    m = kn.Model("slider_crank", parameters={"r": r, "l": l, "g": g},
                 description="A slider-crank: crank, connecting rod and a slider on the x "
                             "axis; the loop closes at the wrist pin B, cut automatically.",
                 simulation={"t_end": 10.0, "n_points": 1001, "method": "auto",
                             "rtol": 1e-12, "atol": 1e-12})
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Revolute("O", q0=theta0, qd0=thetad0))
    m.connect("ground.frame", "O.frame_a")
    tip = _rod(m, "crank", "O.frame_b", "r", masses[0], r)
    beta0 = np.arcsin(-r * np.sin(theta0) / l)
    m.add(mb.Revolute("A", q0_guess=float(beta0 - theta0)))
    m.connect(tip, "A.frame_a")
    rod_tip = _rod(m, "rod", "A.frame_b", "l", masses[1], l)
    x0 = r * np.cos(theta0) + np.sqrt(l ** 2 - (r * np.sin(theta0)) ** 2)
    m.add(mb.Prismatic("slider", axis=[1, 0, 0], q0_guess=float(x0)))
    m.add(mb.RigidBody("slider_mass", mass=masses[2]))
    m.connect("ground.frame", "slider.frame_a")
    m.connect("slider.frame_b", "slider_mass.frame_a")
    m.add(mb.Revolute("B", q0_guess=float(-beta0)))
    m.connect(rod_tip, "B.frame_a")
    m.connect("B.frame_b", "slider.frame_b")
    if probes:
        m.add(kn.Probe("crank_probe", quantities=["angle", "speed"]))
        m.add(kn.Probe("piston", quantities=["position", "velocity", "force"]))
        m.add(kn.Probe("wrist_pin", quantities=["force"]))
        m.connect("crank_probe.port", "O.axis")
        m.connect("piston.port", "slider.axis")
        m.connect("wrist_pin.port", "B.frame_b")
    return m


def spatial_fourbar(theta0=0.0, thetad0=2.0, c=0.7, probes=True):
    """An RSUR spatial four-bar under gravity -z: crank about z at the origin (0.3 m),
    rocker about x at (0.4, 0.9, 0.3) (length ``c``, upright at rest), coupler from a Universal
    joint at the crank tip to a Spherical joint at the rocker tip, as long as the two tips are
    apart at theta = 0 and an upright rocker; the Spherical is cut (three position equations)."""
    b = float(np.sqrt(0.1 ** 2 + 0.9 ** 2 + (0.3 + c) ** 2))
    m = kn.Model("spatial_fourbar", parameters={"g": G},
                 description="A spatial RSUR four-bar: crank about z, rocker about x, coupler "
                             "on a Universal joint at the crank and a ball joint at the rocker "
                             "(cut automatically: three position constraints).",
                 simulation={"t_end": 10.0, "n_points": 1001, "method": "auto",
                             "rtol": 1e-10, "atol": 1e-12})
    m.add(mb.Ground("ground", gravity=[0, 0, "-g"]))
    m.add(mb.Revolute("A", axis=[0, 0, 1], q0=theta0, qd0=thetad0))
    m.connect("ground.frame", "A.frame_a")
    tip = _rod(m, "crank", "A.frame_b", "0.3", 1.0, 0.3)
    m.add(mb.Universal("U", n_a=[0, 0, 1], n_b=[0, 1, 0], q0_guess=[1.4, -0.7]))
    m.connect(tip, "U.frame_a")
    coupler_tip = _rod(m, "coupler", "U.frame_b", repr(round(b, 12)), 1.5, b)
    m.add(mb.FixedTranslation("base", r=[0.4, 0.9, 0.3]))
    m.connect("ground.frame", "base.frame_a")
    m.add(mb.Revolute("D", axis=[1, 0, 0], q0_guess=0.0))
    m.connect("base.frame_b", "D.frame_a")
    rocker_tip = _rod(m, "rocker", "D.frame_b", repr(c), 1.0, c, along=(0, 0, 1))
    m.add(mb.Spherical("S"))
    m.connect(coupler_tip, "S.frame_a")
    m.connect("S.frame_b", rocker_tip)
    if probes:
        m.add(kn.Probe("crank_probe", quantities=["angle", "speed"]))
        m.add(kn.Probe("rocker_probe", quantities=["angle", "speed"]))
        m.add(kn.Probe("ball", quantities=["position", "force"]))
        m.connect("crank_probe.port", "A.axis")
        m.connect("rocker_probe.port", "D.axis")
        m.connect("ball.port", "S.frame_b")
    return m


def dzhanibekov(w0=(0.01, 5.0, 0.01), inertia=(1.0, 2.0, 3.0), mass=1.0, t_end=20.0):
    """A free body spinning about its intermediate principal axis: it flips over and over
    (the Dzhanibekov effect). The probe ``tip`` marks a point 1 m along the body's y axis."""
    m = kn.Model("dzhanibekov",
                 description="A free rigid body (FreeMotion) spun about its intermediate "
                             "principal axis, without gravity: the spin axis flips every few "
                             "seconds (the Dzhanibekov or tennis-racket effect). Energy and "
                             "angular momentum are conserved.",
                 simulation={"t_end": t_end, "n_points": 2001, "method": "auto",
                             "rtol": 1e-10, "atol": 1e-12})
    m.add(mb.Ground("ground", gravity=[0, 0, 0]))
    m.add(mb.FreeMotion("free", w0=list(w0)))
    m.add(mb.RigidBody("body", mass=mass, inertia=list(inertia)))
    m.add(mb.FixedTranslation("marker", r=[0, 1, 0]))
    m.add(kn.Probe("tip", quantities=["position"]))
    m.add(kn.Probe("spin", quantities=["angular_velocity"]))
    for a, b in [("ground.frame", "free.frame_a"), ("free.frame_b", "body.frame_a"),
                 ("free.frame_b", "marker.frame_a"), ("tip.port", "marker.frame_b"),
                 ("spin.port", "free.frame_b")]:
        m.connect(a, b)
    return m


def spring_pendulum(c=200.0, s0=1.0, mass=1.0, angle0=0.6, stretch0=1.2, g=G):
    """A point mass on a swinging, sliding arm (Revolute about z, Prismatic along -y)
    suspended from the pivot by a multibody Spring of unstretched length ``s0``."""
    m = kn.Model("spring_pendulum", parameters={"c": c, "s0": s0, "m": mass, "g": g},
                 description="An elastic pendulum: a point mass held by a line spring "
                             "(multibody.Spring) from the pivot, free to swing and stretch.",
                 simulation={"t_end": 10.0, "n_points": 1001, "method": "auto",
                             "rtol": 1e-10, "atol": 1e-12})
    m.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    m.add(mb.Revolute("swing", q0=angle0))
    m.add(mb.Prismatic("stretch", axis=[0, -1, 0], q0=stretch0))
    m.add(mb.RigidBody("bob", mass="m"))
    m.add(mb.Spring("spring", c="c", s_unstretched="s0"))
    m.add(kn.Probe("bob_probe", quantities=["position", "velocity"]))
    m.add(kn.Probe("anchor", quantities=["force"]))
    for a, b in [("ground.frame", "swing.frame_a"), ("swing.frame_b", "stretch.frame_a"),
                 ("stretch.frame_b", "bob.frame_a"), ("spring.frame_a", "ground.frame"),
                 ("spring.frame_b", "stretch.frame_b"), ("bob_probe.port", "stretch.frame_b"),
                 ("anchor.port", "spring.frame_a")]:
        m.connect(a, b)
    return m


def fourbar_chain(n, theta0=1.0):
    """``n`` four-bars, each hung from the rocker tip of the one before (the first from the
    ground): n degrees of freedom, n loops."""
    m = kn.Model(f"fourbar_chain{n}", parameters={"a": 0.3, "b": 1.0, "c": 0.8, "d": 1.0})
    m.add(mb.Ground("ground", gravity=[0, -G, 0]))
    frame = "ground.frame"
    for i in range(n):
        m.add(mb.Revolute(f"A{i}", q0=theta0 if i == 0 else 0.0))
        m.connect(frame, f"A{i}.frame_a")
        tip = _rod(m, f"crank{i}", f"A{i}.frame_b", "a", 1.0, 0.3)
        guess = fourbar_guesses(theta0 if i == 0 else 0.0)
        m.add(mb.Revolute(f"B{i}", q0_guess=guess[0]))
        m.connect(tip, f"B{i}.frame_a")
        coupler_tip = _rod(m, f"coupler{i}", f"B{i}.frame_b", "b", 2.0, 1.0)
        m.add(mb.FixedTranslation(f"base{i}", r=["d", 0, 0]))
        m.connect(frame, f"base{i}.frame_a")
        m.add(mb.Revolute(f"D{i}", q0_guess=guess[1]))
        m.connect(f"base{i}.frame_b", f"D{i}.frame_a")
        rocker_tip = _rod(m, f"rocker{i}", f"D{i}.frame_b", "c", 1.5, 0.8)
        m.add(mb.Revolute(f"C{i}", q0_guess=guess[2]))
        m.connect(coupler_tip, f"C{i}.frame_a")
        m.connect(f"C{i}.frame_b", rocker_tip)
        # the next four-bar hangs from the rocker tip, its ground line along the rocker
        frame = rocker_tip
    return m


def fourbar_guesses(theta, a=0.3, b=1.0, c=0.8, d=1.0):
    """Relative joint angles (B, D, C) of the open assembly at crank angle ``theta``."""
    B = np.array([a * np.cos(theta), a * np.sin(theta)])
    D = np.array([d, 0.0])
    f = np.linalg.norm(D - B)
    alpha = np.arccos((b * b + f * f - c * c) / (2 * b * f))
    phi = np.arctan2(*(D - B)[::-1]) + alpha
    C = B + b * np.array([np.cos(phi), np.sin(phi)])
    psi = np.arctan2(*(C - D)[::-1])
    return float(phi - theta), float(psi), float(psi - phi)


FILES = {"fourbar": fourbar, "slider_crank": slider_crank, "spatial_fourbar": spatial_fourbar,
         "dzhanibekov": dzhanibekov, "spring_pendulum": spring_pendulum}


if __name__ == "__main__":
    for name, build in FILES.items():
        path = ROOT / "models" / f"{name}.json"
        build().save(path)
        json.loads(path.read_text())
        print("wrote", path)
