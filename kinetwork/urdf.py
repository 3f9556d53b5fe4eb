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

import json
import math
import os
import re
import unicodedata
import xml.etree.ElementTree as ET

import numpy as np

from .components import multibody as mb
from .components import rotational, translational
from .components.probe import Probe
from .errors import ModelError
from .graph.model import Model

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
#: what a probe on each joint records (the 1-D flange for 1-DOF joints, frame_b otherwise)
PROBED = {"rotational": ["angle", "speed", "torque"],
          "translational": ["position", "velocity", "force"],
          "frame": ["position", "orientation", "velocity", "angular_velocity"]}
NAME_ROOM = 180                   # a base name's length, leaving room for suffixes


def from_urdf(path, probes=False, floating=False, gravity=(0.0, 0.0, -9.81), name=None):
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
    robot = _read(source)
    where = os.path.basename(source)
    problems = []
    links, joints, materials = _parse(robot, problems)
    tree = _tree(links, joints, problems) if not problems else None
    if not problems:
        _carried(links, joints, tree[1], problems)
    if problems:
        raise ModelError([f"{where}: {p}" for p in problems])
    model = _build(robot.get("name") or "robot", links, joints, tree, materials,
                   probes=probes, floating=floating, gravity=gravity, name=name, where=where)
    model.validate()
    return model


def cli_import(args):
    """``kinetwork import ROBOT.urdf -o MODEL.json``: write the model; the exit code."""
    gravity = (0.0, 0.0, -9.81) if args.gravity is None else tuple(args.gravity)
    model = from_urdf(args.source, probes=args.probes, floating=args.floating, gravity=gravity)
    model.save(args.out)
    parts = model.components.values()
    states = sum(c.dof for c in parts if c.role == "joint")
    bodies = sum(1 for c in parts if c.role == "body" and c.mass != 0)
    print(f"{args.out}: {model.name!r}, {states} degrees of freedom, {bodies} bodies, "
          f"{len(model.components)} components")
    return 0


def _q(text, limit=80):
    """``text`` in double quotes, as in ``joint "elbow": ...`` (cut past ``limit``)."""
    if text is None:
        return "(none)"
    text = str(text)
    return json.dumps(text if len(text) <= limit else text[:limit] + "...", ensure_ascii=False)


# -- reading ---------------------------------------------------------------------------------
def _read(source):
    """The <robot> element of the file."""
    try:
        with open(source, "rb") as fh:
            text = fh.read()
    except FileNotFoundError:
        raise ModelError(f"{_q(source)}: no such file") from None
    except OSError as exc:
        raise ModelError(f"{_q(source)}: cannot read: {exc.strerror or exc}") from None
    where = os.path.basename(source)
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        line, column = exc.position
        raise ModelError(f"{where}: malformed XML at line {line}, column {column + 1}: "
                         f"{str(exc).split(':')[0]}") from None
    if _tag(root) != "robot":
        raise ModelError(f"{where}: the root element is <{_tag(root)}>, not <robot>: "
                         f"not a URDF file")
    if any("xacro" in (el.tag or "") for el in root.iter()):
        raise ModelError(f"{where}: holds xacro macros: expand it first "
                         f"(xacro robot.urdf.xacro > robot.urdf)")
    return root


def _tag(el):
    return el.tag.rpartition("}")[2] if isinstance(el.tag, str) else ""


def _floats(el, attr, n, where, problems, default=None):
    """``n`` finite numbers from attribute ``attr`` of ``el`` (``default`` when absent)."""
    text = None if el is None else el.get(attr)
    if text is None:
        if default is None:
            problems.append(f"{where}: missing {attr}")
        return default
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        values = None
    if values is None or len(values) != n or not all(map(math.isfinite, values)):
        problems.append(f"{where} {attr}: expected {n} finite number{'s' * (n > 1)}, "
                        f"got {_q(text, 60)}")
        return default
    return values if n > 1 else values[0]


def _origin(parent, where, problems):
    """(xyz, rpy) of the <origin> child of ``parent`` (zeros when absent)."""
    el = parent.find("origin")
    place = f"{where} origin"
    return (_floats(el, "xyz", 3, place, problems, [0.0] * 3),
            _floats(el, "rpy", 3, place, problems, [0.0] * 3))


def _attrs(el, where, problems):
    """The numeric attributes of ``el`` as a dict (for limits and dynamics kept as data)."""
    if el is None:
        return None
    out = {}
    for key, text in el.attrib.items():
        try:
            out[key] = float(text)
        except ValueError:
            out[key] = text
        if isinstance(out[key], float) and not math.isfinite(out[key]):
            problems.append(f"{where} {key}: must be finite, got {_q(text, 40)}")
            out[key] = None
    return out


def _parse(robot, problems):
    """Links, joints (dicts by URDF name, in file order) and named materials' colours."""
    materials = {}
    for el in robot.findall("material"):
        colour = _colour(el, f"material {_q(el.get('name'))}", problems)
        if el.get("name") is not None and colour is not None:
            materials[el.get("name")] = colour
    links = {}
    for el in robot.findall("link"):
        name = el.get("name")
        if not name:
            problems.append(f"link #{len(links) + 1}: missing name")
            continue
        where = f"link {_q(name)}"
        if name in links:
            problems.append(f"{where}: defined twice")
            continue
        links[name] = {"inertial": _inertial(el.find("inertial"), where, problems),
                       "visuals": [v for v in (_visual(v, f"{where} visual", problems)
                                               for v in el.findall("visual")) if v]}
    joints = {}
    for el in robot.findall("joint"):
        name = el.get("name")
        if not name:
            problems.append(f"joint #{len(joints) + 1}: missing name")
            continue
        where = f"joint {_q(name)}"
        if name in joints:
            problems.append(f"{where}: defined twice")
            continue
        kind = el.get("type")
        if kind not in JOINT_TYPES:
            problems.append(f"{where}: type {_q(kind)} is not one of {', '.join(JOINT_TYPES)}")
            continue
        ends = {}
        for end in ("parent", "child"):
            tag = el.find(end)
            ends[end] = None if tag is None else tag.get("link")
            if not ends[end]:
                problems.append(f"{where}: missing <{end} link=\"...\"/>")
        xyz, rpy = _origin(el, where, problems)
        axis = _floats(el.find("axis"), "xyz", 3, f"{where} axis", problems, [1.0, 0.0, 0.0])
        size = math.sqrt(sum(a * a for a in axis))
        if size < 1e-12 and kind not in ("fixed", "floating"):
            problems.append(f"{where} axis: must not be zero")
        joints[name] = {
            "type": kind, **ends, "xyz": xyz, "rpy": rpy,
            "axis": [a / size for a in axis] if size >= 1e-12 else axis,
            "data": {key: value for key, value in (
                (tag, _attrs(el.find(tag), f"{where} {tag}", problems))
                for tag in ("limit", "dynamics", "mimic", "safety_controller", "calibration"))
                if value is not None}}
    for name, j in joints.items():
        for key in ("damping", "friction"):
            value = j["data"].get("dynamics", {}).get(key)
            if value is not None and not (isinstance(value, float) and value >= 0):
                problems.append(f"joint {_q(name)} dynamics {key}: must be a number >= 0, "
                                f"got {_q(str(value), 40)}")
    if not links:
        problems.append("no <link>: a robot has at least one")
    return links, joints, materials


def _inertial(el, where, problems):
    """(mass, r_cm, inertia about the CM in link axes) of an <inertial>, or None."""
    if el is None:
        return None
    where = f"{where} inertial"
    n = len(problems)
    mass = _floats(el.find("mass"), "value", 1, f"{where} mass", problems)
    xyz, rpy = _origin(el, where, problems)
    tensor = el.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    values = {k: _floats(tensor, k, 1, f"{where} inertia", problems, 0.0) for k in keys}
    if tensor is None:
        problems.append(f"{where}: missing <inertia>")
    if len(problems) > n:
        return None
    if mass < 0:
        problems.append(f"{where} mass: must be >= 0, got {mass:g}")
    v = values
    inertia = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                        [v["ixz"], v["iyz"], v["izz"]]])
    # all zero is a point mass (or a massless link); moments breaking the triangle
    # inequality are left to the model's validation, which warns of them as idealised
    eig = np.linalg.eigvalsh(inertia)
    if np.any(inertia != 0) and eig[0] <= 0:
        problems.append(f"{where} inertia: must be positive definite, its principal "
                        f"moments are {', '.join(f'{e:.6g}' for e in eig)}")
    R = rpy_matrix(rpy)
    return mass, xyz, R @ inertia @ R.T


def _colour(el, where, problems):
    """'#rrggbb' of a <material>'s <color rgba>, or None."""
    rgba = _floats(el.find("color"), "rgba", 4, f"{where} color", problems, [])
    if not rgba:
        return None
    return "#" + "".join(f"{round(min(max(c, 0.0), 1.0) * 255):02x}" for c in rgba[:3])


def _visual(el, where, problems):
    """A visual as a dict: kind, size (box extents, cylinder [length, radius], sphere
    [radius]) or mesh file and scale, origin, colour or material name; None if unknown."""
    xyz, rpy = _origin(el, where, problems)
    out = {"xyz": xyz, "rpy": rpy, "color": None, "material": None}
    material = el.find("material")
    if material is not None:
        out["color"] = _colour(material, f"{where} material", problems)
        out["material"] = material.get("name")
    geometry = el.find("geometry")
    shape = None if geometry is None else next(iter(geometry), None)
    kind = None if shape is None else _tag(shape)
    if kind == "box":
        out["size"] = _floats(shape, "size", 3, f"{where} box", problems)
    elif kind == "cylinder":
        out["size"] = [_floats(shape, "length", 1, f"{where} cylinder", problems),
                       _floats(shape, "radius", 1, f"{where} cylinder", problems)]
    elif kind == "sphere":
        out["size"] = [_floats(shape, "radius", 1, f"{where} sphere", problems)]
    elif kind == "mesh":
        out["filename"] = shape.get("filename")
        out["scale"] = _floats(shape, "scale", 3, f"{where} mesh", problems, [1.0] * 3)
    else:
        return None
    out["kind"] = kind
    if "size" in out and any(s is None or s < 0 for s in out["size"]):
        if all(s is not None for s in out["size"]):
            problems.append(f"{where} {kind}: sizes must be >= 0, got {out['size']}")
        return None
    return out


# -- the tree ----------------------------------------------------------------------------------
def _tree(links, joints, problems):
    """(root link, joints ordered parents first); problems for a graph that is no tree."""
    parent_of = {}
    for name, j in joints.items():
        where = f"joint {_q(name)}"
        for end in ("parent", "child"):
            if j[end] and j[end] not in links:
                problems.append(f"{where}: {end} link {_q(j[end])} does not exist")
        if j["child"] in parent_of:
            problems.append(f"{where}: link {_q(j['child'])} is already the child of joint "
                            f"{_q(parent_of[j['child']])}: a kinematic loop (URDF "
                            f"describes trees)")
        elif j["child"] == j["parent"] and j["child"]:
            problems.append(f"{where}: link {_q(j['child'])} is its own parent")
        else:
            parent_of[j["child"]] = name
    if problems:
        return None
    roots = [link for link in links if link not in parent_of]
    children = {}
    for name, j in joints.items():
        children.setdefault(j["parent"], []).append(name)
    order = _depth_first(roots, children, joints)
    reached = set(roots) | {joints[name]["child"] for name in order}
    lost = [link for link in links if link not in reached]
    if lost:                          # every lost link has a parent: they sit on cycles
        name = parent_of[lost[0]]
        problems.append(f"joint {_q(name)}: closes a kinematic loop through links "
                        f"{', '.join(_q(l) for l in lost)} (URDF describes trees)")
    elif len(roots) != 1:
        problems.append(f"{len(roots)} root links ({', '.join(_q(r) for r in roots)}): "
                        f"a robot is one tree, joined to a single root link")
    return roots[0] if roots else None, order


def _carried(links, joints, order, problems):
    """A moving joint must move some mass: with none beyond it, its acceleration is
    undefined (a singular mass matrix)."""
    heavy = {link: L["inertial"] is not None and (L["inertial"][0] > 0 or
                                                  np.any(L["inertial"][2] != 0))
             for link, L in links.items()}
    for name in reversed(order):              # children before parents
        heavy[joints[name]["parent"]] |= heavy[joints[name]["child"]]
    for name in order:
        J = joints[name]
        if J["type"] != "fixed" and not heavy[J["child"]]:
            problems.append(f"joint {_q(name)}: moves link {_q(J['child'])}, which has no "
                            f"mass and carries none: its motion is undefined (give the link an "
                            f"<inertial>, or make the joint fixed)")


def _depth_first(roots, children, joints):
    """The joints reached from ``roots``, parents first, each subtree whole, in file order."""
    order, stack = [], [j for r in reversed(roots) for j in reversed(children.get(r, []))]
    while stack:
        name = stack.pop()
        order.append(name)
        stack.extend(reversed(children.get(joints[name]["child"], [])))
    return order


# -- the model ---------------------------------------------------------------------------------
def _build(robot, links, joints, tree, materials, *, probes, floating, gravity, name, where):
    """The Model of a checked URDF tree (see the module's docstring for what maps to what)."""
    root, order = tree
    names = _Names()
    ground_name = names.claim("ground")
    jname = {j: names.claim(j) for j in joints}
    lname = {link: names.claim(link) for link in links}
    description = (f"{robot}, imported from the URDF file {where}: {len(links)} links, "
                   f"{len(joints)} joints. What URDF gives that is not imposed here (joint "
                   f"limits, friction, mimic couplings) is kept in layout.<joint>.urdf; the "
                   f"map from URDF names to components in layout.{ground_name}.urdf.")
    model = Model(name or robot, description=description)
    model.add(mb.Ground(ground_name, gravity=list(gravity)))
    frame = {root: f"{ground_name}.frame"}
    mapped, base = {}, None
    if floating:
        free = model.add(mb.FreeMotion(names.claim(f"{lname[root]}_floating")))
        model.connect(frame[root], f"{free.name}.frame_a")
        frame[root], base = f"{free.name}.frame_b", free.name
        model.layout[free.name] = {"urdf": {"joint": None, "type": "floating",
                                            "note": f"joins the root link {root} to the world"}}
        if probes:
            _probe(model, names, free, "frame_b", "frame")
    for j in order:
        J = joints[j]
        at = _fixed(model, names, f"{jname[j]}_origin", J["xyz"], rpy_matrix(J["rpy"]),
                    frame[J["parent"]])
        data = {"urdf": {"joint": j, "type": J["type"], **J["data"]}}
        joint = _joint(jname[j], J)
        if joint is None:                 # fixed: the origin is all of it
            frame[J["child"]] = at
            mapped[j] = None if at == frame[J["parent"]] else at.partition(".")[0]
            if mapped[j] is not None:
                model.layout[mapped[j]] = data
            continue
        model.add(joint)
        model.connect(at, f"{joint.name}.frame_a")
        frame[J["child"]] = f"{joint.name}.frame_b"
        mapped[j] = joint.name
        model.layout[joint.name] = data
        _damper(model, names, joint, J["data"].get("dynamics", {}).get("damping", 0.0))
        if probes:
            _probe(model, names, joint, *(("axis", joint.domain) if joint.dof == 1
                                          else ("frame_b", "frame")))
    visuals = []
    for link, L in links.items():
        if L["inertial"] is not None:
            mass, r_cm, inertia = L["inertial"]
            if mass > 0 or np.any(inertia != 0):
                body = model.add(mb.RigidBody(lname[link], mass=mass, r_cm=r_cm,
                                              inertia=inertia.tolist()))
                model.connect(f"{body.name}.frame_a", frame[link])
                model.layout[body.name] = {"urdf": {"link": link}}
        for visual in L["visuals"]:
            visuals.append(_look(model, names, lname[link], visual, frame[link], materials,
                                 link))
    model.layout[ground_name] = {"urdf": {
        "robot": robot, "file": where, "root": root, "base": base,
        "links": {link: frame[link] for link in links}, "joints": mapped,
        "visuals": visuals}}
    return model


def _fixed(model, names, base, xyz, R, at):
    """The frame ``xyz``, ``R`` from the frame ``at``: a FixedRotation, a FixedTranslation or
    ``at`` itself, as little as it takes."""
    axis, angle = axis_angle(R)
    if angle == 0.0 and not any(xyz):
        return at
    if angle == 0.0:
        part = mb.FixedTranslation(names.claim(base), r=list(xyz))
    else:
        part = mb.FixedRotation(names.claim(base), r=list(xyz), axis=axis, angle=angle)
    model.add(part)
    model.connect(at, f"{part.name}.frame_a")
    return f"{part.name}.frame_b"


def _joint(name, J):
    """The kinetwork joint of a URDF joint (None for a fixed one)."""
    kind, axis = J["type"], J["axis"]
    if kind in ("revolute", "continuous"):
        return mb.Revolute(name, axis=axis)
    if kind == "prismatic":
        return mb.Prismatic(name, axis=axis)
    if kind == "planar":              # q[0] along the joint frame's x made normal to axis
        n_x = [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0]
        return mb.Planar(name, n=axis, n_x=n_x)
    if kind == "floating":
        return mb.FreeMotion(name)
    return None


def _damper(model, names, joint, d):
    """URDF's viscous joint damping: a Damper between the joint's support and axis."""
    if not d or joint.dof != 1:
        return
    lib = rotational if joint.domain == "rotational" else translational
    damper = model.add(lib.Damper(names.claim(f"{joint.name}_damper"), d=d))
    model.connect(f"{damper.name}.flange_a", f"{joint.name}.support")
    model.connect(f"{damper.name}.flange_b", f"{joint.name}.axis")


def _probe(model, names, joint, port, domain):
    probe = model.add(Probe(names.claim(f"{joint.name}_probe"), quantities=PROBED[domain]))
    model.connect(f"{probe.name}.port", f"{joint.name}.{port}")


#: turns a frame so that its x axis lies along the original z: a URDF cylinder's axis is z,
#: a RigidBody's cylinder runs along x
Z_TO_X = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
#: a visual turned by less than this [rad] is drawn unturned (rpy="0 1.5708 0" of a
#: cylinder along x leaves a rounding error, not a rotation worth a part)
LOOKS_ANGLE = 1e-9


def _look(model, names, base, visual, at, materials, link):
    """The visual as data ({"link", "frame", "kind", "xyz", "rpy", "color", "component"},
    and URDF's "size", "length" and "radius", or "filename" and "scale"); a box, cylinder or
    sphere is drawn by a massless RigidBody ``component`` as well."""
    colour = visual["color"] or materials.get(visual["material"])
    data = {"link": link, "frame": at, "kind": visual["kind"], "xyz": visual["xyz"],
            "rpy": visual["rpy"], "color": colour, "component": None}
    if visual["kind"] == "mesh":
        data.update(filename=visual["filename"], scale=visual["scale"])
        return data
    size, R = visual["size"], rpy_matrix(visual["rpy"])
    if visual["kind"] == "box":
        data["size"] = shape_size = list(size)
    elif visual["kind"] == "cylinder":
        data.update(length=size[0], radius=size[1])
        shape_size = [size[0], 2 * size[1], 2 * size[1]]
        R = R @ Z_TO_X
    else:
        data["radius"] = size[0]
        shape_size = [2 * size[0]] * 3
    turned = axis_angle(R)[1] > LOOKS_ANGLE
    frame = (_fixed(model, names, f"{base}_visual_origin", visual["xyz"], R, at) if turned
             else at)
    body = model.add(mb.RigidBody(names.claim(f"{base}_visual"), mass=0.0,
                                  r_cm=[0.0] * 3 if turned else list(visual["xyz"]),
                                  shape=visual["kind"], shape_size=shape_size, color=colour))
    model.connect(f"{body.name}.frame_a", frame)
    data["component"] = body.name
    return data


# -- names --------------------------------------------------------------------------------------
class _Names:
    """kinetwork identifiers for URDF names: letters, digits and underscores; a clash with a
    name already given gets ``_2``, ``_3``, ... in the order names are asked for."""

    def __init__(self):
        self.taken = set()

    def claim(self, text):
        base = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
        base = re.sub(r"[^A-Za-z0-9_]", "_", base)[:NAME_ROOM] or "_"
        if base[0].isdigit():
            base = "_" + base
        name, k = base, 2
        while name in self.taken:
            name, k = f"{base}_{k}", k + 1
        self.taken.add(name)
        return name


# -- rotations ----------------------------------------------------------------------------------
def rpy_matrix(rpy):
    """URDF's roll-pitch-yaw: about the fixed x, then y, then z: Rz(yaw) Ry(pitch) Rx(roll)."""
    (cr, sr), (cp, sp), (cy, sy) = ((math.cos(a), math.sin(a)) for a in rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_angle(R):
    """(unit axis, angle in [0, pi]) of the rotation matrix ``R``, accurate near 0 and pi
    (through the quaternion, Shepperd's choice of its largest component)."""
    t = np.trace(R)
    diag = np.diag(R)
    k = int(np.argmax(diag))
    if t >= diag[k]:
        w = math.sqrt(max(1.0 + t, 0.0)) / 2
        v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / (4 * w)
    else:
        i, j, m = k, (k + 1) % 3, (k + 2) % 3
        v = np.zeros(3)
        v[i] = math.sqrt(max(1.0 + R[i, i] - R[j, j] - R[m, m], 0.0)) / 2
        v[j] = (R[j, i] + R[i, j]) / (4 * v[i])
        v[m] = (R[m, i] + R[i, m]) / (4 * v[i])
        w = (R[m, j] - R[j, m]) / (4 * v[i])
    if w < 0:
        w, v = -w, -v
    s = float(np.linalg.norm(v))
    if s < 1e-300:
        return [0.0, 0.0, 1.0], 0.0
    return (v / s).tolist(), 2 * math.atan2(s, w)
