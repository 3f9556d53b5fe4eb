"""A mass on a spring written without model parameters, alone and inside a subsystem: the
scene of component parameters by path (``"spring.c"``, ``"cyl3.mass.m"``), with its closed
form."""

import numpy as np

import kinetwork as kn


def oscillator(c=4.0, m=1.0, name="oscillator"):
    """A mass on a spring, no model parameter: x = 0.1 cos(sqrt(c/m) t)."""
    model = kn.Model(name)
    fixed = model.add(kn.translational.Fixed("fixed"))
    spring = model.add(kn.translational.Spring("spring", c=c))
    mass = model.add(kn.translational.Mass("mass", m=m, s0=0.1, v0=0.0))
    probe = model.add(kn.Probe("probe", quantities=["position"]))
    model.connect(fixed.flange, spring.flange_a)
    model.connect(spring.flange_b, mass.flange_a)
    model.connect(probe.port, mass.flange_a)
    return model


def stage():
    """A subsystem: the oscillator's spring (stiffness k) and mass, its base exposed."""
    inner = kn.Model("stage", parameters={"k": 4.0})
    spring = inner.add(kn.translational.Spring("spring", c="k"))
    mass = inner.add(kn.translational.Mass("mass", m=1.0, s0=0.1, v0=0.0))
    probe = inner.add(kn.Probe("probe", quantities=["position"]))
    inner.connect(spring.flange_b, mass.flange_a)
    inner.connect(probe.port, mass.flange_a)
    inner.expose("base", "spring.flange_a")
    outer = kn.Model("rig")
    fixed = outer.add(kn.translational.Fixed("fixed"))
    outer.add(kn.Subsystem("cyl3", inner, params={"k": 9.0}))
    outer.connect(fixed.flange, "cyl3.base")
    return outer


def closed_form(t, c, m):
    return 0.1 * np.cos(np.sqrt(c / m) * t)
