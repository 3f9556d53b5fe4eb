"""Building the kinetwork Model of a checked URDF tree (see the package's docstring for what
maps to what)."""

import re
import unicodedata

import numpy as np

from ..components import multibody as mb
from ..components import rotational, translational
from ..components.probe import Probe
from ..graph.model import Model
from .meshes import resolve
from .rotations import axis_angle, rpy_matrix

#: what a probe on each joint records (the 1-D flange for 1-DOF joints, frame_b otherwise)
PROBED = {"rotational": ["angle", "speed", "torque"],
          "translational": ["position", "velocity", "force"],
          "frame": ["position", "orientation", "velocity", "angular_velocity"]}
NAME_ROOM = 180                   # a base name's length, leaving room for suffixes
#: a joint that reaches its limit stays there (no bounce): URDF gives no restitution, and the
#: simulators that read URDF (Gazebo, MuJoCo, PyBullet) hold a joint at its limit
STOP_RESTITUTION = 0.0


def build(robot, links, joints, tree, materials, *, probes, floating, gravity, name, where,
          limits=True, folder="."):
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
        stops = _range(J) if limits else None
        joint = _joint(jname[j], J, stops)
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
        dynamics = J["data"].get("dynamics", {})
        _between(model, names, joint, "damper", "Damper", dynamics.get("damping", 0.0))
        _between(model, names, joint, "friction", "Friction", dynamics.get("friction", 0.0))
        if stops is not None:
            _between(model, names, joint, "limits", "Stop", *stops)
        if probes:
            _probe(model, names, joint, *(("axis", joint.domain) if joint.dof == 1
                                          else ("frame_b", "frame")))
    visuals, bodies = [], {}
    for link, L in links.items():
        if L["inertial"] is not None:
            mass, r_cm, inertia = L["inertial"]
            if mass > 0 or np.any(inertia != 0):
                body = model.add(mb.RigidBody(lname[link], mass=mass, r_cm=r_cm,
                                              inertia=inertia.tolist()))
                model.connect(f"{body.name}.frame_a", frame[link])
                model.layout[body.name] = {"urdf": {"link": link}}
                bodies[link] = body.name
        for visual in L["visuals"]:
            visuals.append(_look(model, names, lname[link], visual, frame[link], materials,
                                 link, folder))
    model.layout[ground_name] = {"urdf": {
        "robot": robot, "file": where, "root": root, "base": base,
        "links": {link: frame[link] for link in links}, "joints": mapped,
        "visuals": visuals},
        # what the animation draws: the mesh files found, on their links' frames
        "meshes": [_placed(v, bodies.get(v["link"])) for v in visuals if v.get("path")]}
    if not any(gravity):
        model.layout[ground_name]["up"] = [0.0, 0.0, 1.0]      # URDF's convention: z up
    return model


def _placed(visual, body):
    """A mesh visual as the animation reads it (``kinetwork.animation``'s mesh entries): the
    file on its link's frame, placed by its origin and scaled; it stands in for the link's
    body, which is then not drawn as a sphere."""
    return {"path": visual["path"], "frame": visual["frame"],
            "position": list(visual["xyz"]), "rotation": rpy_matrix(visual["rpy"]).tolist(),
            "scale": list(visual["scale"]), "color": visual["color"],
            "replaces": [body] if body else [], "source": visual["filename"]}


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


def _range(J):
    """(lower, upper) of a revolute or prismatic joint's position limits, or None (a
    continuous joint, no <limit>, or URDF's default lower = upper = 0: no range given)."""
    limit = J["data"].get("limit", {})
    lower, upper = limit.get("lower", 0.0), limit.get("upper", 0.0)
    if J["type"] not in ("revolute", "prismatic") or not lower < upper:
        return None
    return lower, upper


def _joint(name, J, stops=None):
    """The kinetwork joint of a URDF joint (None for a fixed one); within ``stops``, it starts
    at the zero position clamped into them (URDF has no start; 0 is its reference pose)."""
    kind, axis = J["type"], J["axis"]
    start = {}
    if stops is not None and not stops[0] <= 0.0 <= stops[1]:
        start = {"q0": min(max(0.0, stops[0]), stops[1])}
    if kind in ("revolute", "continuous"):
        return mb.Revolute(name, axis=axis, **start)
    if kind == "prismatic":
        return mb.Prismatic(name, axis=axis, **start)
    if kind == "planar":              # q[0] along the joint frame's x made normal to axis
        n_x = [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0]
        return mb.Planar(name, n=axis, n_x=n_x)
    if kind == "floating":
        return mb.FreeMotion(name)
    return None


def _between(model, names, joint, suffix, kind, *values):
    """A 1-D element ``<joint>_<suffix>`` between a 1-DOF joint's support and its axis, in the
    joint's domain: a Damper (``values``: d), a friction with stiction (the Coulomb force or
    torque) or a Stop (lower, upper); none for a damping or friction of zero."""
    if joint.dof != 1 or (kind != "Stop" and not values[0]):
        return
    turning = joint.domain == "rotational"
    lib = rotational if turning else translational
    name = names.claim(f"{joint.name}_{suffix}")
    if kind == "Damper":
        part = lib.Damper(name, d=values[0])
    elif kind == "Friction":
        cls, key = ((rotational.BearingFriction, "tau_c") if turning
                    else (translational.Friction, "f_c"))
        part = cls(name, **{key: values[0]})
    else:
        low, high = ("phi_min", "phi_max") if turning else ("s_min", "s_max")
        part = lib.Stop(name, **{low: values[0], high: values[1], "e": STOP_RESTITUTION})
    model.add(part)
    a, b = ("support", "flange") if kind == "Friction" else ("flange_a", "flange_b")
    model.connect(f"{part.name}.{a}", f"{joint.name}.support")
    model.connect(f"{part.name}.{b}", f"{joint.name}.axis")


def _probe(model, names, joint, port, domain):
    probe = model.add(Probe(names.claim(f"{joint.name}_probe"), quantities=PROBED[domain]))
    model.connect(f"{probe.name}.port", f"{joint.name}.{port}")


#: turns a frame so that its x axis lies along the original z: a URDF cylinder's axis is z,
#: a RigidBody's cylinder runs along x
Z_TO_X = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
#: a visual turned by less than this [rad] is drawn unturned (rpy="0 1.5708 0" of a
#: cylinder along x leaves a rounding error, not a rotation worth a part)
LOOKS_ANGLE = 1e-9


def _look(model, names, base, visual, at, materials, link, folder):
    """The visual as data ({"link", "frame", "kind", "xyz", "rpy", "color", "component"},
    and URDF's "size", "length" and "radius", or "filename", "scale" and the "path" of the
    file found, or None); a box, cylinder or sphere is drawn by a massless RigidBody
    ``component`` as well."""
    colour = visual["color"] or materials.get(visual["material"])
    data = {"link": link, "frame": at, "kind": visual["kind"], "xyz": visual["xyz"],
            "rpy": visual["rpy"], "color": colour, "component": None}
    if visual["kind"] == "mesh":
        data.update(filename=visual["filename"], scale=visual["scale"],
                    path=resolve(visual["filename"], folder))
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
