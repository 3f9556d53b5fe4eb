"""Multibody components (kinetwork/components/multibody.py): the hooks the equations call,
each on its own: transforms, loop closures, cut preferences, mass properties, line-force laws."""

import casadi as ca
import numpy as np
import pytest

import kinetwork as kn

mb = kn.multibody


def numbers(expr):
    """A CasADi expression without symbols, as numpy."""
    return np.array(ca.evalf(ca.SX(expr)), dtype=float)


def test_joint_direction_n_is_given_as_axis_in_files_and_keywords():
    joint = kn.multibody.Revolute("j", axis=[1, 0, 0])
    assert joint.axis.path == "j.axis"                 # the flange port
    assert joint.n == [1, 0, 0]                        # the direction parameter, as MSL's n
    assert joint.given == {"n": [1, 0, 0]} and joint.written_params() == {"axis": [1, 0, 0]}


def test_inertia_diagonal_shorthand():
    body = kn.multibody.RigidBody("b", mass=1.0, inertia=[1, 2, 3])
    assert body.inertia == [[1, 0, 0], [0, 2, 0], [0, 0, 3]]


def test_mass_properties():
    body = mb.RigidBody("b", mass=2.0, r_cm=[0.1, 0.2, 0.3], inertia=[1, 2, 3])
    m, c, inertia = body.mass_properties()
    assert m == 2.0
    np.testing.assert_array_equal(numbers(c).ravel(), [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(numbers(inertia), np.diag([1.0, 2.0, 3.0]))


# -- transforms and closures ------------------------------------------------------------------

def test_transform_conventions():
    R, p = mb.Revolute("r", axis=[0, 0, 2]).transform(ca.DM([np.pi / 2]))
    np.testing.assert_allclose(numbers(R) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_array_equal(numbers(p).ravel(), 0)
    R, p = mb.Prismatic("s", axis=[0, 3, 4]).transform(ca.DM([5.0]))
    np.testing.assert_array_equal(numbers(R), np.eye(3))
    np.testing.assert_allclose(numbers(p).ravel(), [0, 3, 4], atol=1e-15)
    R, p = mb.FixedRotation("f", r=[1, 2, 3], axis=[1, 0, 0], angle=np.pi).transform(None)
    np.testing.assert_allclose(numbers(R), np.diag([1, -1, -1]), atol=1e-15)
    np.testing.assert_array_equal(numbers(p).ravel(), [1, 2, 3])


#: a component of every kind that keeps the full 12 closure rows, and coordinates of it
FULL_CLOSURE = [
    (mb.Revolute("j", axis=[1, 2, 3]), [0.7]),
    (mb.Prismatic("j", axis=[0, 1, 1]), [0.4]),
    (mb.Universal("j", n_a=[1, 0, 0], n_b=[0, 1, 1]), [0.3, -1.1]),
    (mb.Cylindrical("j", axis=[1, 1, 0]), [2.0, -0.5]),
    (mb.Planar("j", n=[0, 0, 1], n_x=[1, 1, 0]), [0.2, -0.3, 1.4]),
    (mb.FixedTranslation("j", r=[1, 2, 3]), []),
    (mb.FixedRotation("j", r=[1, 0, 0], axis=[0, 1, 0], angle=0.8), []),
]


@pytest.mark.parametrize("part, q", FULL_CLOSURE, ids=lambda v: getattr(v, "type_name", ""))
def test_a_cut_joint_or_part_closes_at_its_own_transform(part, q):
    """12 rows (3 of position, 9 of the rotation matrix) that vanish where the transform at
    q puts frame_b, and not elsewhere."""
    q = ca.DM(q)
    R, p = part.transform(q)
    residual = numbers(part.closure(R, p, q))
    assert residual.shape == (12, 1)
    np.testing.assert_allclose(residual, 0, atol=1e-14)
    moved = numbers(part.closure(R, p + ca.DM([0, 0, 0.1]), q))
    turned = numbers(part.closure(R @ ca.DM(np.diag([1.0, -1.0, -1.0])), p, q))
    assert np.max(np.abs(moved[:3])) == pytest.approx(0.1)
    assert np.max(np.abs(moved[3:])) < 1e-14
    assert np.max(np.abs(turned[3:])) > 1 and np.max(np.abs(turned[:3])) < 1e-14


def test_a_cut_spherical_joint_constrains_the_position_only():
    joint = mb.Spherical("s")
    q = ca.DM([1.0, 0.0, 0.0, 0.0])
    turned = ca.DM(np.diag([1.0, -1.0, -1.0]))
    residual = numbers(joint.closure(turned, ca.DM([0.1, -0.2, 0.3]), q))
    np.testing.assert_array_equal(residual.ravel(), [0.1, -0.2, 0.3])
    np.testing.assert_array_equal(numbers(joint.closure(turned, ca.DM.zeros(3), q)), 0)


def test_a_cut_free_motion_constrains_nothing():
    joint = mb.FreeMotion("f")
    residual = joint.closure(ca.DM.eye(3), ca.DM([1.0, 2.0, 3.0]), ca.DM.zeros(7))
    assert residual.shape == (0, 1)


def test_cut_preference_orders_the_candidates_of_a_loop():
    """Lowest is cut first: a free motion (cutting it removes nothing), then a spherical
    joint (three position rows), then the other joints; a rigid part never before a joint."""
    rank = {cls: cls.cut_preference for cls in (
        mb.FreeMotion, mb.Spherical, mb.Revolute, mb.Prismatic, mb.Universal, mb.Cylindrical,
        mb.Planar, mb.FixedTranslation, mb.FixedRotation)}
    assert rank[mb.FreeMotion] < rank[mb.Spherical] < rank[mb.Revolute]
    assert {rank[c] for c in (mb.Revolute, mb.Prismatic, mb.Universal, mb.Cylindrical,
                              mb.Planar)} == {rank[mb.Revolute]}
    assert rank[mb.FixedTranslation] == rank[mb.FixedRotation] > rank[mb.Revolute]


def test_a_loop_is_cut_where_its_joints_prefer_unless_one_is_marked():
    """The spatial four-bar is cut at its Spherical joint (preference 1, over the Revolute
    and Universal joints of the loop); the planar one at a revolute, and at the one marked
    ``cut`` when there is one, whatever the ranking."""
    from scenes import fourbar, spatial_fourbar
    assert [c.component.name for c in spatial_fourbar().validate().cuts] == ["S"]
    model = fourbar(probes=False)
    assert [c.component.name for c in model.validate().cuts] == ["C"]
    model.components["B"].cut = True
    assert [c.component.name for c in model.validate().cuts] == ["B"]


# -- initial values, rates --------------------------------------------------------------------

def test_initial_values_of_joints():
    assert mb.Revolute("r", q0=0.3, qd0=-1).initial() == ([0.3], [-1])
    assert mb.Universal("u").initial() == ([None, None], [None, None])
    q0, w0 = mb.Spherical("s", angles0=[0, 0, np.pi / 2], w0=[1, 2, 3]).initial()
    np.testing.assert_allclose([float(v) for v in q0], [np.cos(np.pi / 4), 0, 0,
                                                        np.sin(np.pi / 4)], atol=1e-15)
    assert w0 == [1, 2, 3]
    q0, v0 = mb.FreeMotion("f", r0=[1, 2, 3], v0=[4, 5, 6]).initial()
    assert q0[:3] == [1, 2, 3] and v0 == [4, 5, 6, 0, 0, 0]


def test_quaternion_joints_integrate_their_angular_velocity():
    """qdot = 1/2 q (0, w): at the identity, a rate about z moves only the z entry."""
    rate = numbers(mb.Spherical("s").rate(ca.DM([1, 0, 0, 0]), ca.DM([0, 0, 2.0])))
    np.testing.assert_allclose(rate.ravel(), [0, 0, 0, 1.0], atol=1e-15)
    free = numbers(mb.FreeMotion("f").rate(ca.DM([0, 0, 0, 1, 0, 0, 0]),
                                            ca.DM([1, 2, 3, 0, 0, 2.0])))
    np.testing.assert_allclose(free.ravel(), [1, 2, 3, 0, 0, 0, 1.0], atol=1e-15)


# -- line forces ------------------------------------------------------------------------------

@pytest.mark.parametrize("s, s_d", [(1.5, 0.0), (0.2, -3.0), (2.0, 0.7)])
def test_line_spring_damper_is_spring_plus_damper(s, s_d):
    both = mb.SpringDamper("sd", c=40.0, d=3.0, s_unstretched=0.5)
    spring = mb.Spring("s", c=40.0, s_unstretched=0.5)
    damper = mb.Damper("d", d=3.0)
    assert both.law(s, s_d) == pytest.approx(spring.law(s, s_d) + damper.law(s, s_d))
    assert spring.law(0.5, 10.0) == 0.0                        # unstretched: no tension
    assert spring.law(1.5, 0.0) == pytest.approx(40.0)          # stretched: pulls
