"""The seed scene of the paper: the double pendulum with a spring-damper at the shoulder,
built through the public API (``models/double_pendulum.json`` is the same scene as a file)."""

import kinetwork as kn

SEED_PARAMS = {"L1": 1.0, "L2": 1.0, "m1": 1.0, "m2": 1.0, "c": 1.0, "d": 1.0, "g": 9.8}


def double_pendulum(q0=(0.05, 0.05), probes=True, qd0=None, inertia=None, **params):
    """The seed scene: point masses at mid-link, spring-damper at the shoulder.

    ``q0``, ``qd0`` give the initial angles and rates (numbers or expressions); ``inertia``
    optionally gives each link a rotary inertia about z at its centre of mass (the seed's
    links have none); ``params`` override model parameters or add new ones.
    """
    m = kn.Model("double_pendulum", parameters={**SEED_PARAMS, **params})
    speeds = [{} if qd0 is None else {"qd0": qd0[i]} for i in range(2)]
    links = [{} if inertia is None else {"inertia": [[0, 0, 0], [0, 0, 0], [0, 0, inertia[i]]]}
             for i in range(2)]
    m.add(kn.multibody.Ground("ground", gravity=[0, "-g", 0]))
    m.add(kn.multibody.Revolute("shoulder", axis=[0, 0, 1], q0=q0[0], **speeds[0]))
    m.add(kn.multibody.Revolute("elbow", axis=[0, 0, 1], q0=q0[1], **speeds[1]))
    m.add(kn.multibody.FixedTranslation("link1", r=[0, "-L1", 0]))
    m.add(kn.multibody.RigidBody("mass1", mass="m1", r_cm=[0, "-L1/2", 0], **links[0]))
    m.add(kn.multibody.RigidBody("mass2", mass="m2", r_cm=[0, "-L2/2", 0], **links[1]))
    m.add(kn.rotational.SpringDamper("spring", c="c", d="d"))
    wiring = [("ground.frame", "shoulder.frame_a"), ("shoulder.frame_b", "mass1.frame_a"),
              ("shoulder.frame_b", "link1.frame_a"), ("link1.frame_b", "elbow.frame_a"),
              ("elbow.frame_b", "mass2.frame_a"), ("spring.flange_a", "shoulder.support"),
              ("spring.flange_b", "shoulder.axis")]
    if probes:
        quantities = ["angle", "speed", "acceleration", "torque"]
        m.add(kn.Probe("probe1", quantities=quantities))
        m.add(kn.Probe("probe2", quantities=quantities))
        wiring += [("probe1.port", "shoulder.axis"), ("probe2.port", "elbow.axis")]
    for a, b in wiring:
        m.connect(a, b)
    return m
