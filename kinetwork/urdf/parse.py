"""Reading a URDF file: its links, joints and materials as plain data, checked, every
problem named by its element (the standard library's ``xml.etree``; the URDF libraries on PyPI
check no more and bring mesh stacks this does not need)."""

import json
import math
import os
import xml.etree.ElementTree as ET

import numpy as np

from ..errors import ModelError
from .rotations import rpy_matrix

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def _q(text, limit=80):
    """``text`` in double quotes, as in ``joint "elbow": ...`` (cut past ``limit``)."""
    if text is None:
        return "(none)"
    text = str(text)
    return json.dumps(text if len(text) <= limit else text[:limit] + "...", ensure_ascii=False)


def read(source):
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


def parse(robot, problems):
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
def tree(links, joints, problems):
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


def carried(links, joints, order, problems):
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
