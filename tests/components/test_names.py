"""Every parameter ``help()`` names reads back, and writes, as an attribute of that name.

Walks every component type of the registry: each parameter its docstring lists (the section
``help(cls)`` shows) is given a value other than its default, and must read back under its
own name with that value, in SI units; assigning it by that name must land too. Where a
parameter and a port would share a name, Modelica's naming keeps them apart (a joint's
direction ``n``, its flange ``axis``), and the old spelling is still accepted.
"""

import re

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.components.base import REGISTRY

TYPES = sorted(REGISTRY)
_ENTRY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*) : ", re.M)


def documented(cls):
    """The parameter names of the Parameters section of ``help(cls)``'s docstring."""
    doc = cls.__doc__
    if "\nParameters\n----------\n" not in doc:
        return []
    section = doc.split("\nParameters\n----------\n", 1)[1].split("\n\n", 1)[0]
    return _ENTRY.findall(section)


def candidates(spec):
    """Values to try for a parameter, none equal to its default."""
    kind, shape = spec.kind, spec.shape
    if kind == "bool":
        out = [not spec.default if isinstance(spec.default, bool) else True]
    elif kind == "choice":
        out = list(spec.choices)
    elif kind == "color":
        out = ["#123456"]
    elif kind == "name":
        out = ["other"]
    elif kind == "names":
        out = [list(spec.choices[:1])] if spec.choices else [["a"], ["b"]]
    elif kind == "table":
        out = [[[0.0, 0.0], [1.0, 2.0]]]
    elif kind == "table2d":
        out = [[[0.0, 1.0, 2.0], [1.0, 1.0, 2.0], [2.0, 3.0, 4.0]]]
    elif kind == "vector":
        out = [[0.5, 2.0], [1.5]]
    elif kind == "expression":
        out = [1.25]
    elif shape == ():
        out = [0.37, 1.7, 0.9, 0.05, -0.4, 3.0, 60.0, 0.0, 1.0]
    elif shape == (2,):
        out = [[0.3, 0.2], [1.0, 2.0]]
    elif shape == (3,):
        out = [[0.3, 0.4, 1.2], [0.0, 1.0, 0.0], [1.0, 2.0, 3.0]]
    else:
        out = [[[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.5]]]
    return [v for v in out if v != spec.default]


#: parameters that are given only together with another (a Ground's field with its type)
COMPANIONS = {("multibody.Ground", "field"): {"gravity_type": "expression"}}


def build(cls, key=None, value=None):
    """An instance with every required parameter given (and ``key`` given ``value``)."""
    params = dict(COMPANIONS.get((cls.type_name, key), {}))
    for name, spec in cls.params.items():
        if spec.required and name != key:
            params[name] = candidates(spec)[0] if spec.kind != "real" or spec.shape else 1.0
    if key is not None:
        params[key] = value
    return cls("c", **params)


def cases():
    for type_name in TYPES:
        cls = REGISTRY[type_name]
        for key in documented(cls):
            yield pytest.param(type_name, key, id=f"{type_name}.{key}")


def given_value(cls, key):
    """A value ``key`` takes alone (bounds hold), and the instance made with it."""
    tries = [[0.0, 0.0, "-9.81*(1 + z/6.4e6)"]] if (cls.type_name, key) == (
        "multibody.Ground", "field") else candidates(cls.params[key])
    for value in tries:
        try:
            return value, build(cls, key, value)
        except kn.ModelError:
            continue
    raise AssertionError(f"{cls.type_name}.{key}: no candidate value was accepted")


def same(a, b):
    numbers = (int, float)
    if isinstance(a, (list, tuple)) and np.asarray(a).dtype.kind in "iuf":
        return np.allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool):
        return np.isclose(a, b, rtol=1e-15, atol=0)
    return a == b


def test_the_walk_covers_every_type_and_parameter():
    listed = {(t, k) for t in TYPES for k in documented(REGISTRY[t])}
    declared = {(t, k) for t in TYPES for k in REGISTRY[t].params}
    assert listed == declared          # help() lists exactly the declared parameters
    assert len(TYPES) > 80 and len(listed) > 250


@pytest.mark.parametrize("type_name, key", list(cases()))
def test_every_documented_parameter_reads_back_by_its_name(type_name, key):
    cls = REGISTRY[type_name]
    value, comp = given_value(cls, key)
    read = getattr(comp, key)
    assert not callable(read), f"{type_name}.{key} reads as {read!r}"
    spec = cls.params[key]
    expected = spec.si(spec.normalize(value, key))
    assert same(read, expected), f"{type_name}.{key}: gave {value!r}, read {read!r}"
    # and writes by the same name, into what is saved and simulated
    again = build(cls)
    setattr(again, key, value)
    assert same(getattr(again, key), expected) and same(again.given[key], comp.given[key])


@pytest.mark.parametrize("type_name", ["multibody.Revolute", "multibody.Prismatic"])
def test_a_joint_direction_is_n_as_in_modelica_and_axis_still_reads_from_files(
        type_name, tmp_path):
    cls = REGISTRY[type_name]
    joint = cls("j", n=[0.0, 1.0, 0.0])
    assert joint.n == [0.0, 1.0, 0.0] and joint.axis.path == "j.axis"    # flange stays
    old = cls("j", axis=[0.0, 1.0, 0.0])        # the API contract's keyword
    assert old.n == [0.0, 1.0, 0.0]
    model = kn.Model("m")
    model.add(kn.multibody.Ground("g"))
    model.add(cls("j", axis=[0, 1, 0]))
    model.add(cls("k", n=[1, 0, 0]))
    model.connect("g.frame", "j.frame_a")
    model.add(kn.multibody.RigidBody("b", mass=1.0, r_cm=[1, 0, 0]))
    model.connect("j.frame_b", "k.frame_a")
    model.connect("k.frame_b", "b.frame_a")
    model.save(tmp_path / "m.json")
    text = (tmp_path / "m.json").read_text()
    assert '"axis": [' in text and '"n": [' in text      # each saved as it was written
    again = kn.load(tmp_path / "m.json")
    assert again.components["j"].n == [0, 1, 0] and again.components["k"].n == [1, 0, 0]
