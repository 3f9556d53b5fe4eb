"""Physical validation: bodies that no rigid body can be, and mass matrices that cannot be
inverted, refused with the place named."""

import numpy as np
import pytest

import kinetwork as kn
from scenes import double_pendulum

mb = kn.multibody


@pytest.mark.parametrize("inertia, message", [
    ([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "mass1.inertia: must be symmetric"),
    ([1, -1, 1], "mass1.inertia: must be positive semi-definite; its principal moments are "
                 "-1, 1, 1"),
])
def test_impossible_inertias_are_refused(inertia, message):
    model = double_pendulum()
    model.components["mass1"].inertia = inertia      # structure checked here, physics below
    with pytest.raises(kn.ModelError, match=message.replace("(", r"\(")):
        model.compile()


@pytest.mark.parametrize("inertia, message", [
    ([1, 1, 3], "mass1.inertia: its principal moments 1, 1, 3 break the triangle inequality"),
    ([[2, 0.9, 0], [0.9, 2, 0], [0, 0, 4.5]], "break the triangle inequality"),
    ([0.001, 1.16, 0.001], "break the triangle inequality"),      # MSL RobotR3's body b1
])
def test_idealised_inertias_warn_once_and_simulate(inertia, message):
    """MSL's own examples give parts that turn about one axis inertias no rigid body has:
    warned (naming the body), and the model simulates with them, as Modelica does: about z,
    the seed's link 1 adds its I_zz to the shoulder's inertia (checked against the
    closed-form M of the seed plus that moment)."""
    model = double_pendulum()
    model.components["mass1"].inertia = inertia
    with pytest.warns(kn.IdealisedInertiaWarning, match=message.replace("(", r"\(")):
        system = model.compile()
    q = [0.3, -0.7]
    added = system.mass_matrix(q) - double_pendulum().compile().mass_matrix(q)
    izz = np.asarray(inertia if np.ndim(inertia) == 2 else np.diag(inertia))[2, 2]
    np.testing.assert_allclose(added, [[izz, 0], [0, 0]], rtol=1e-12, atol=1e-14)


def test_an_idealised_inertia_that_leaves_a_joint_without_mass_is_refused():
    """diag(2, 0, 0) (MSL ActuatedDrive's) on a massless body turning about z: accepted as a
    part, then the singular mass matrix refused by name. (A tensor with zero moments is the
    usual planar idealisation: not warned about, or every planar model would warn.)"""
    model = kn.Model("spin")
    model.add(mb.Ground("ground"))
    model.add(mb.Revolute("hinge", axis=[0, 0, 1]))
    model.add(mb.RigidBody("rotor", mass=0.0, inertia=[2, 0, 0]))
    model.connect("ground.frame", "hinge.frame_a")
    model.connect("hinge.frame_b", "rotor.frame_a")
    with pytest.raises(kn.ModelError, match="singular.*hinge"):
        model.compile()
    model.components["hinge"].set_param("axis", [1, 0, 0])    # about its one moment: it turns
    assert model.compile().mass_matrix([0.0])[0, 0] == 2.0


@pytest.mark.parametrize("inertia", [[0, 0, 0.2], [0.1, 0.1, 0.2], [0.3, 0.2, 0.5]])
def test_idealised_and_limiting_inertias_are_accepted(inertia):
    """A planar link given only its moment about the joint axis, and bodies on the edge of the
    inequality (a thin disc: I_z = I_x + I_y), are fine."""
    model = double_pendulum(inertia=(0.1, 0.2))
    model.components["mass1"].inertia = inertia
    # accepted, and in the mass matrix: about z, the links' moments add to the point masses'
    # M (both joints turn link 2, only the shoulder link 1)
    q = [0.3, -0.7]
    added = model.compile().mass_matrix(q) - double_pendulum().compile().mass_matrix(q)
    i1, i2 = inertia[2], 0.2
    np.testing.assert_allclose(added, [[i1 + i2, i2], [i2, i2]], rtol=1e-12, atol=1e-14)


def test_a_joint_that_moves_nothing_is_refused_by_name():
    """A slider carrying a body of zero mass: the mass matrix is singular at the start."""
    model = double_pendulum()
    model.add(mb.Prismatic("slide", axis=[1, 0, 0]))
    model.add(mb.RigidBody("ghost", mass=0.0))
    model.connect("mass2.frame_a", "slide.frame_a")
    model.connect("slide.frame_b", "ghost.frame_a")
    with pytest.raises(kn.ModelError, match=r"mass matrix is singular at the initial state: "
                                            r"slide move\(s\) no mass"):
        model.compile()
