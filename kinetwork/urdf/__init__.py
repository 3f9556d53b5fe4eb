"""URDF robots as kinetwork models: :func:`from_urdf` and ``kinetwork import``.

A URDF file is a tree of links joined by joints. Each joint's ``origin`` (xyz, then
roll-pitch-yaw about the fixed x, y, z axes) places the joint frame in the parent link's
frame, and the child link's frame is the joint frame moved by the joint. So a joint becomes

- a ``FixedRotation`` (or ``FixedTranslation``, or nothing) ``<joint>_origin`` for its origin,
  the rotation as one axis and angle;
- the joint itself on its axis (unit length, in the joint frame): revolute and continuous
  ``Revolute``, prismatic ``Prismatic``, planar ``Planar`` (the plane normal to the axis,
  q[0] along the joint frame's x projected into it), floating ``FreeMotion``; a fixed joint is
  its origin only;
- with ``dynamics damping`` > 0, a rotational or translational ``Damper`` ``<joint>_damper``
  between the joint's support and axis (the viscous damping the file asks for);

and a link with an ``inertial`` becomes a ``RigidBody`` of the link's name on the link frame:
the centre of mass at the inertial origin, the inertia turned from the inertial frame into the
link frame (R I R^T). The root link is fixed to the ``Ground`` (or, ``floating=True``, joined to
it by a ``FreeMotion`` ``<root>_floating``). Box, cylinder and sphere visuals become massless
``RigidBody`` parts ``<link>_visual`` with their shape, size and colour (a cylinder drawn along
the URDF cylinder's z axis), on a fixed part ``<link>_visual_origin`` where their origin needs
one.

Kept as data, not physics, in the model's ``layout`` (which files keep as written): on each
joint ``{"urdf": {"joint", "type", "limit", "dynamics", "mimic", ...}}`` (position, effort and
velocity limits, friction and mimic couplings are not imposed); on the ground the robot's name,
the map from URDF names to kinetwork ones (a joint to its component, a link to the frame that
carries it) and every visual, meshes by file name. Collision geometry, transmissions and
Gazebo tags are ignored.

The file is read with the standard library's ``xml.etree.ElementTree`` and checked here: the
URDF libraries on PyPI check no more (a negative mass or a joint to a missing link passes
them) and bring mesh stacks this module does not need.
"""

import os

from ..errors import ModelError
from .build import PROBED, Z_TO_X, build
from .parse import JOINT_TYPES, carried, parse, read, tree
from .rotations import axis_angle, rpy_matrix

__all__ = ["from_urdf", "cli_import", "rpy_matrix", "axis_angle", "JOINT_TYPES", "PROBED"]


def from_urdf(path, probes=False, floating=False, gravity=(0.0, 0.0, -9.81), name=None,
              limits=True):
    """The kinetwork model of the robot described in the URDF file ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        URDF file (xacro already expanded).
    probes : bool
        A probe ``<joint>_probe`` on every moving joint: angle, speed, torque (revolute);
        position, velocity, force (prismatic); pose and velocities of frame_b (planar,
        floating).
    floating : bool
        Join the root link to the ground by a FreeMotion (a free-flying base) instead of
        fixing it there.
    gravity : 3 numbers, m/s^2
        Gravity of the Ground, in the root link's frame at rest (URDF's z is up).
    name : str, optional
        Model name (default: the robot's name).
    limits : bool
        Impose the revolute and prismatic joints' position limits as hard end stops (a
        ``Stop`` ``<joint>_limits`` between the joint's support and axis; a joint whose zero
        lies outside its limits starts at the nearer one). False leaves them as data only.

    Returns
    -------
    Model
        Validated; ``model.layout["ground"]["urdf"]`` maps URDF names to kinetwork ones.

    Raises
    ------
    ModelError
        A missing or unreadable file, malformed XML, or a robot that is no valid URDF tree
        (a joint to a missing link, a kinematic loop, a negative mass, an inertia that is not
        positive definite, ...), each problem naming its element.
    """
    source = os.fspath(path)
    robot = read(source)
    where = os.path.basename(source)
    problems = []
    links, joints, materials = parse(robot, problems)
    shape = tree(links, joints, problems) if not problems else None
    if not problems:
        carried(links, joints, shape[1], problems)
    if problems:
        raise ModelError([f"{where}: {p}" for p in problems])
    model = build(robot.get("name") or "robot", links, joints, shape, materials,
                 probes=probes, floating=floating, gravity=gravity, name=name, where=where,
                  limits=limits)
    model.validate()
    return model


def cli_import(args):
    """``kinetwork import ROBOT.urdf -o MODEL.json`` (see :mod:`.command`)."""
    from .command import cli_import as run
    return run(args)
