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
  between the joint's support and axis (the viscous damping the file asks for); with
  ``dynamics friction`` > 0, a ``BearingFriction`` (or translational ``Friction``)
  ``<joint>_friction`` there (Coulomb friction with stiction);
- for a revolute or prismatic joint with ``limit lower < upper`` (``limits=True``, the
  default), a hard ``Stop`` ``<joint>_limits`` there with restitution 0: the joint comes to
  rest on a limit it reaches, as the simulators that read URDF hold it; a joint whose zero
  lies outside its limits starts at the nearer limit;

and a link with an ``inertial`` becomes a ``RigidBody`` of the link's name on the link frame:
the centre of mass at the inertial origin, the inertia turned from the inertial frame into the
link frame (R I R^T). The root link is fixed to the ``Ground`` (or, ``floating=True``, joined to
it by a ``FreeMotion`` ``<root>_floating``). Box, cylinder and sphere visuals become massless
``RigidBody`` parts ``<link>_visual`` with their shape, size and colour (a cylinder drawn along
the URDF cylinder's z axis), on a fixed part ``<link>_visual_origin`` where their origin needs
one. Mesh visuals (STL, OBJ, DAE) are found as ROS tools find them (``package://`` through
``ROS_PACKAGE_PATH``, ``AMENT_PREFIX_PATH`` or the folders above the URDF: ``meshes.py``) and
listed for the animation in ``layout.<ground>.meshes``, which draws them (with trimesh) in
place of their links' bodies. With zero gravity the animation keeps URDF's z up.

Kept as data in the model's ``layout`` (which files keep as written): on each joint
``{"urdf": {"joint", "type", "limit", "dynamics", "mimic", ...}}`` (effort and velocity
limits and mimic couplings are not imposed); on the ground the robot's name, the map from
URDF names to kinetwork ones (a joint to its component, a link to the frame that carries it)
and every visual, meshes by file name and the path found. Collision geometry, transmissions
and Gazebo tags are ignored.

The file is read with the standard library's ``xml.etree.ElementTree`` and checked here: the
URDF libraries on PyPI check no more (a negative mass or a joint to a missing link passes
them) and bring mesh stacks this module does not need.
"""


from .build import PROBED, Z_TO_X
from .command import cli_import
from .load import from_urdf
from .parse import JOINT_TYPES
from .rotations import axis_angle, rpy_matrix

__all__ = ["from_urdf", "cli_import", "rpy_matrix", "axis_angle", "JOINT_TYPES", "PROBED",
           "Z_TO_X"]
