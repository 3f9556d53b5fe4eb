"""A subsystem's parameter values that cannot be evaluated once an instance's numbers are in
(a division by zero, a logarithm of a negative number, a negative power of zero) are refused as a
ModelError naming the inner component and parameter by path, never a ZeroDivisionError or a
ValueError from the flattening (the fuzz test of mutated files found one)."""

import json

import pytest

import kinetwork as kn
from graph.test_subsystem import link_model


def one_link(mass, L=0.0):
    """A ground and one link subsystem whose body's mass is ``mass`` (in the link's L)."""
    link = link_model()
    link.components["bob"]._values["mass"] = mass
    top = kn.Model("top")
    top.add(kn.multibody.Ground("ground"))
    upper = top.add(kn.Subsystem("upper", link, params={"L": L}))
    top.connect("ground.frame", upper.frame_a)
    return top


@pytest.mark.parametrize("mass, why", [("1/L", "division by zero"),
                                       ("1 + log(L - 1)", "math domain error"),
                                       ("L**-1", "cannot be raised to a negative power")])
def test_a_value_that_cannot_be_evaluated_is_refused_by_path(mass, why):
    top = one_link(mass)
    with pytest.raises(kn.ModelError,
                       match=rf"upper/bob\.mass = '.*': cannot be evaluated.*{why}"):
        top.compile()
    one_link(mass, L=2.0).compile()          # the same definition with L = 2 is a model


def test_from_a_file_too():
    """A file's definition whose body's mass is 1/L, placed with L = 0."""
    doc = json.loads(kn.dumps(one_link(1.0, L=0.0)))
    bob = next(c for c in doc["definitions"]["link"]["components"] if c["name"] == "bob")
    bob["params"]["mass"] = "1/L"
    with pytest.raises(kn.ModelError, match=r'upper/bob\.mass \(definitions\.link\.'
                       r'components\[2\] "bob" params\.mass\) = .1/L.: cannot'):
        kn.loads(json.dumps(doc)).compile()
