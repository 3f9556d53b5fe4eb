"""``from_urdf``: a URDF file read, checked and built into a Model."""

import os

from ..errors import ModelError
from .build import build
from .parse import carried, parse, read, tree


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
                  limits=limits, folder=os.path.dirname(os.path.abspath(source)))
    model.validate()
    return model
