"""The Animation of a run: the poses of every frame, from one mapped CasADi call of the
kinematics frame probes read, and the shapes drawn on them (see ``kinetwork.animation``)."""

import math

import casadi as ca
import numpy as np

from ..equations.system import pointwise
from ..errors import ModelError
from .meshes import mesh as mesh_file

FORMAT, VERSION = "kinetwork.animation", 1
#: the players draw the small axes of every frame when there are at most this many
FRAMES_SHOWN = 24
COLORS = {"joint": "#e8453c", "rod": "#9b9b9b", "body": "#0080ff", "spring": "#e0a030",
          "damper": "#5a5a5a", "grid": "#c8ccd2", "mesh": "#b8bdc6"}
#: a frame that travels more than this many times as far as the median frame (and than the
#: scene's size) ran away: the view is framed without it
RUNAWAY = 8.0
_X, _Y, _Z = np.eye(3)


def animation_data(results, fps=None, model=None, resolution=None, arrays=False):
    """The Animation of ``results``: the scene and the poses of its frames (the format is in
    ``kinetwork.animation``).

    Parameters
    ----------
    results : kinetwork.Results
    fps : float, optional
        Resample the poses to this many frames per second (positions linearly,
        orientations along the shorter arc); default: the results' own grid.
    model : kinetwork.Model or kinetwork.System, optional
        What made the results, when they do not say (``results.system``).
    resolution : float, optional
        Round positions to this fraction of ``scale`` and quaternions to this much, at a
        power of ten (1e-7: far below a pixel at any zoom), for a player that draws them: the
        JSON is half as long and twice as fast to write; default: every digit.
    arrays : bool, optional
        Leave each frame's ``position`` and ``quaternion`` as numpy arrays, for an encoder
        that writes arrays itself (the studio's: 0.03 s of CPU less for EngineV6's poses than
        lists of Python floats); default: lists.

    Raises
    ------
    ModelError
        No model known, or results that are not of that model.
    """
    system = _system(results, model)
    params = results.settings.get("params") or None
    values = system.model.numeric_values(params)
    t = np.asarray(results.t, dtype=float)
    # resampled: the poses are computed only at the results' times the new grid falls
    # between (a run of millions of points animated at 30 frames per second)
    kept = _between(t, fps) if fps is not None else slice(None)
    t = t[kept]
    frames, index, positions, rotations = _frame_poses(system, t, results.states[kept],
                                                       params)
    bodies = {}
    for comp in system.model.components.values():
        k = index.get(system.topology.set_of.get(comp.port_ref("frame_a"))) \
            if hasattr(type(comp), "mass_properties") and "frame_a" in comp.ports else None
        if k is not None:                  # a body: its centre of mass is a frame too
            c = _numbers(comp.bound(values[comp.name]).mass_properties()[1])
            bodies[comp.name] = len(frames)
            frames.append({"name": f"{comp.name}.cm", "ports": []})
            positions.append(positions[k] + rotations[k] @ c)
            rotations.append(rotations[k])
    positions, quats = np.array(positions), _continuous(_quaternions(np.array(rotations)))
    if fps is not None:
        t, positions, quats = _resample(t, positions, quats, fps)
    kept = _framed(positions)
    scale = _scale(positions[kept], values)
    lo, hi = positions[kept].reshape(-1, 3).min(axis=0), positions[kept].reshape(-1, 3).max(axis=0)
    if resolution is not None and 0 < resolution * scale < math.inf:    # (a run away: inf)
        positions = np.round(positions, _decimals(resolution * scale))
        quats = np.round(quats, _decimals(resolution))
    for frame, pos, quat in zip(frames, positions, quats):
        still = np.all(pos == pos[0]) and np.all(quat == quat[0])
        pos, quat = (pos[:1], quat[:1]) if still else (pos, quat)
        frame["position"], frame["quaternion"] = (pos, quat) if arrays else \
            (pos.tolist(), quat.tolist())
    up = _up(system, values)
    scene = Scene(system, results, values, frames, index, bodies, scale, up, (lo, hi))
    shapes = scene.shapes()
    for shape in shapes:                # a mesh's extent at the start is in view too
        if shape["kind"] == "mesh":
            k = shape["frame"]
            p0, R0 = positions[k, 0], np.asarray(rotations[k])[0]
            corners = p0 + np.reshape(shape["vertices"], (-1, 3)) @ R0.T
            lo, hi = np.minimum(lo, corners.min(axis=0)), np.maximum(hi, corners.max(axis=0))
    return {"format": FORMAT, "version": VERSION, "name": system.model.name,
            "t": t.tolist(), "frames": frames, "shapes": shapes,
            "scale": scale, "bounds": [lo.tolist(), hi.tolist()],
            "view": {"up": up.tolist(), "target": ((lo + hi) / 2).tolist(),
                     "direction": _direction(up, hi - lo).tolist(), "fov": 35}}


def _decimals(step):
    """The decimals of the largest power of ten not above ``step`` (> 0)."""
    return int(-math.floor(math.log10(step)))


def _between(t, fps):
    """The indices of the times ``t`` that the grid of ``fps`` frames per second over them
    falls between (what ``_resample`` interpolates from), in order."""
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0) or len(t) < 2:
        return slice(None)                      # _resample says what is wrong with fps
    count = int(math.floor((t[-1] - t[0]) * fps + 1e-9)) + 1
    if count >= len(t):
        return slice(None)
    grid = t[0] + np.arange(count) / fps
    i = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, len(t) - 2)
    return np.unique(np.concatenate([i, i + 1]))


def _frame_poses(system, t, states, params):
    """(frames, {frame set: index}, positions, rotations) of every frame connection set at
    the times ``t`` and full ``states``: one mapped evaluation of ``System.f_frames`` over
    them; positions (n, 3) and rotations (n, 3, 3) per frame."""
    t, sets = np.asarray(t, dtype=float), system.frame_sets
    if not sets:
        raise ModelError(f"nothing to animate: {system.model.name!r} has no multibody frames")
    if not len(t):
        raise ModelError("nothing to animate: the results hold no time point")
    p = system.param_vector(params)
    out = pointwise(system.f_frames, t[:, None], np.asarray(states), p)[0]
    out = out.reshape(len(t), len(sets), 12).transpose(1, 0, 2)          # set, time, 12
    bad = ~np.all(np.isfinite(out), axis=(0, 2))
    if bad.any():
        raise ModelError(f"cannot animate {system.model.name!r}: its poses are not finite from "
                         f"t = {t[np.argmax(bad)]:g} s on")
    frames = []
    for s in sets:
        ports = [ref.path for ref in system.topology.sets[s] if ref.component.role != "probe"]
        frames.append({"name": ports[0] if ports else f"frame{s}", "ports": ports})
    return (frames, {s: k for k, s in enumerate(sets)}, list(out[..., :3]),
            list(out[..., 3:].reshape(len(sets), len(t), 3, 3)))


def _system(results, model):
    system = model if model is not None else getattr(results, "system", None)
    if system is None:
        raise ModelError("these results do not say which model made them: pass model=... "
                         "(the kn.Model or kn.System that was simulated)")
    if not hasattr(system, "f_frames"):
        system = system.compile()
    names = system.state_names + system.algebraic_names
    if list(results.state_names) != names:
        raise ModelError(f"these results are not of model {system.model.name!r}: their states "
                         f"are {', '.join(results.state_names) or 'none'}, its states "
                         f"{', '.join(names) or 'none'}")
    return system


def _numbers(x):
    return np.asarray(ca.evalf(ca.SX(x)), dtype=float).ravel()


def _quaternions(R):
    """Unit quaternions [w, x, y, z] of rotation matrices (..., 3, 3) (Shepperd's method:
    from the largest of the four squared components, so no division is ill-conditioned)."""
    m = R
    tr = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    squares = np.stack([1 + tr, 1 + 2 * m[..., 0, 0] - tr, 1 + 2 * m[..., 1, 1] - tr,
                        1 + 2 * m[..., 2, 2] - tr], axis=-1)
    pick = np.argmax(squares, axis=-1)
    s = np.sqrt(np.maximum(np.take_along_axis(squares, pick[..., None], -1)[..., 0], 1e-300))
    a, b, c = m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]
    d, e, f = m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0], m[..., 1, 2] + m[..., 2, 1]
    cases = [(s * s, a, b, c), (a, s * s, d, e), (b, d, s * s, f), (c, e, f, s * s)]
    q = np.zeros(R.shape[:-2] + (4,))
    for k, case in enumerate(cases):
        q[pick == k] = np.stack(case, axis=-1)[pick == k]
    q /= 2 * s[..., None]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _continuous(q):
    """Each frame's quaternions with signs chosen so neighbours in time are close (q and -q
    are one orientation): interpolation between samples then takes the short way."""
    flips = np.sum(q[:, 1:] * q[:, :-1], axis=-1) < 0
    signs = np.concatenate([np.ones((len(q), 1)), np.cumprod(np.where(flips, -1.0, 1.0), 1)], 1)
    return q * signs[..., None]


def _resample(t, positions, quats, fps):
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise ModelError(f"fps: must be a finite number > 0, got {fps!r:.40}")
    count = int(math.floor((t[-1] - t[0]) * fps + 1e-9)) + 1
    grid = t[0] + np.arange(count) / fps
    i = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, max(len(t) - 2, 0))
    j = np.minimum(i + 1, len(t) - 1)
    span = np.where(t[j] > t[i], t[j] - t[i], 1.0)
    w = np.clip((grid - t[i]) / span, 0.0, 1.0)[None, :, None]
    pos = positions[:, i] * (1 - w) + positions[:, j] * w
    q = quats[:, i] * (1 - w) + quats[:, j] * w
    return grid, pos, q / np.linalg.norm(q, axis=-1, keepdims=True)


def _scale(positions, values):
    """The model's size: the largest extent of its frame origins over the run; for a scene
    that never spreads (one body at the origin), the longest vector among its parameters."""
    extent = np.ptp(positions.reshape(-1, 3), axis=0).max() if positions.size else 0.0
    if extent > 1e-9:
        return float(extent)
    lengths = [np.linalg.norm(v) for comp in values.values() for k, v in comp.items()
               if k in ("r", "r_cm", "r_shape") and v is not None]
    return float(max(lengths, default=0.0)) or 1.0


def _framed(positions):
    """Which frames the view is framed on: all but those that run away (travel more than
    RUNAWAY times as far as the median frame and than the scene's size at the start), so a
    robot whose free finger falls for ever is not shrunk to a dot; all when all do."""
    if positions.shape[1] < 2:
        return np.ones(len(positions), dtype=bool)
    travel = np.ptp(positions, axis=1).max(axis=1)
    size = np.ptp(positions[:, 0], axis=0).max()
    kept = travel <= RUNAWAY * max(float(np.median(travel)), float(size), 1e-12)
    return kept if kept.any() else np.ones(len(positions), dtype=bool)


def _up(system, values):
    """Up: against gravity; without gravity, the up a model's layout gives (a URDF robot's z),
    else y."""
    world = system.topology.world
    g = np.asarray(values[world.name]["gravity"], dtype=float) if world else np.zeros(3)
    if np.linalg.norm(g) > 0:
        return -g / np.linalg.norm(g) + 0.0
    up = (system.model.layout.get(world.name) or {}).get("up") if world else None
    try:
        up = np.asarray(up, dtype=float).reshape(3)
    except (TypeError, ValueError):
        return _Y.copy()
    return up / np.linalg.norm(up) if np.all(np.isfinite(up)) and np.linalg.norm(up) > 0 \
        else _Y.copy()


def _direction(up, extent):
    """Where the camera looks from: across the plane of the largest horizontal spread (a
    planar mechanism is seen face on), raised and turned a little to show depth."""
    horizontal = [a - np.dot(a, up) * up for a in np.eye(3)]
    horizontal = [h / np.linalg.norm(h) for h in horizontal if np.linalg.norm(h) > 0.3]
    side = max(horizontal, key=lambda h: (abs(h) @ extent, -np.argmax(abs(h))))
    depth = np.cross(side, up)
    d = depth + 0.35 * side + 0.22 * up
    return d / np.linalg.norm(d)


# -- the shapes -----------------------------------------------------------------------------
class Scene:
    """The shapes of a model's components, sized from the model's scale."""

    def __init__(self, system, results, values, frames, index, bodies, scale, up, bounds):
        self.system, self.results, self.values = system, results, values
        self.frames, self.index, self.bodies = frames, index, bodies
        self.L, self.up, self.bounds = scale, up, bounds
        masses = [float(_numbers(c.bound(values[c.name]).mass_properties()[0])[0])
                  for c in system.model.components.values() if c.name in bodies]
        self.heaviest = max(masses, default=0.0)

    def frame(self, comp, port):
        if port not in comp.ports:
            return None
        return self.index.get(self.system.topology.set_of.get(comp.port_ref(port)))

    def shapes(self):
        out = self.ground()
        meshes, replaced = self.meshes()
        out += meshes
        for comp in self.system.model.components.values():
            draw = None if comp.name in replaced else _visual(comp)
            if draw is not None:
                out += [dict(s, component=comp.name) for s in draw(self, comp,
                                                                   self.values[comp.name])
                        if s is not None]
        out += [_axes(k, self.L / 14) for k, f in enumerate(self.frames)
                if not f["name"].endswith(".cm") and k != self.ground_frame()]
        return [s for s in out if not self.covered(s, out)]

    def meshes(self):
        """(the mesh shapes, the components they stand in for) of the mesh files a model's
        layout names: entries ``{"path", "frame": "comp.port", "position", "rotation",
        "scale", "color", "replaces"}`` in a component's ``layout[...]["meshes"]`` (a URDF
        robot's link meshes, on its ground). A file not found or not readable is left out."""
        out, replaced = [], set()
        for entry in self.system.model.layout.values():
            for m in (entry.get("meshes") or []) if isinstance(entry, dict) else []:
                comp, _, port = str(m.get("frame", "")).partition(".")
                k = (self.frame(self.system.model.components[comp], port)
                     if comp in self.system.model.components else None)
                loaded = mesh_file(m["path"]) if k is not None and m.get("path") else None
                if loaded is None:
                    continue
                vertices, triangles = loaded
                R = np.asarray(m.get("rotation", np.eye(3)), dtype=float)
                scale = np.asarray(m.get("scale", [1.0] * 3), dtype=float)
                placed = np.asarray(m.get("position", [0.0] * 3), dtype=float) \
                    + (vertices * scale) @ R.T
                out.append({"kind": "mesh", "frame": k, "component": comp,
                            "color": _color(m.get("color"), COLORS["mesh"]),
                            "vertices": np.round(placed, 6).ravel().tolist(),
                            "faces": triangles.ravel().tolist()})
                replaced.update(m.get("replaces") or [])
        return out, replaced

    def covered(self, shape, shapes):
        """Whether ``shape`` is a body's rod to its centre of mass that lies along another
        rod (a mass half-way along a link): drawn twice, the two would fight."""
        if shape["kind"] != "rod" or shape["to"] not in self.bodies.values():
            return False
        start = lambda k: np.asarray(self.frames[k]["position"][0])     # noqa: E731
        cm = start(shape["to"])
        for rod in shapes:
            if rod is shape or rod["kind"] != "rod" or shape["frame"] not in (rod["frame"],
                                                                              rod["to"]):
                continue
            a, b = start(rod["frame"]), start(rod["to"])
            d = b - a
            s = np.clip(np.dot(cm - a, d) / max(np.dot(d, d), 1e-300), 0, 1)
            if np.linalg.norm(a + s * d - cm) < rod["diameter"]:
                return True
        return False

    def ground_frame(self):
        world = self.system.topology.world
        return self.frame(world, "frame") if world else None

    def ground(self):
        k = self.ground_frame()
        if k is None:
            return []
        lo, hi = self.bounds
        centre = (lo + hi) / 2
        floor = min(np.dot(lo, self.up), np.dot(hi, self.up)) - self.L / 8
        pos = np.asarray(self.frames[k]["position"][0])
        r = centre + (floor - np.dot(centre, self.up)) * self.up - pos
        size = max(1.3 * np.linalg.norm((hi - lo) - np.dot(hi - lo, self.up) * self.up),
                   0.8 * self.L)
        return [{"kind": "grid", "frame": k, "component": None, "color": COLORS["grid"],
                 "r_shape": r.tolist(), "normal": self.up.tolist(), "size": size,
                 "divisions": 10},
                dict(_axes(k, self.L / 6), component=None)]

    # what each kind of component looks like
    def joint(self, comp, v, axis="n"):
        n = unit_vector(_get(v, axis, _Z))
        length, width = self.L / 10, self.L / 20
        return [_shape("cylinder", self.frame(comp, "frame_a"), -n * length / 2, n, length,
                       width, width, COLORS["joint"])]

    def ball(self, comp, v):
        d = self.L / 14
        return [_shape("sphere", self.frame(comp, "frame_a"), np.zeros(3), _X, d, d, d,
                       COLORS["joint"])]

    def rod_joint(self, comp, v):
        """A massless rod with a joint at each end (SphericalSpherical, UniversalSpherical):
        a ball at either end, a thin rod between."""
        d = self.L / 14
        a, b = self.frame(comp, "frame_a"), self.frame(comp, "frame_b")
        ends = [_shape("sphere", f, np.zeros(3), _X, d, d, d, COLORS["joint"]) for f in (a, b)]
        rod = ([{"kind": "rod", "frame": a, "to": b, "diameter": self.L / 40,
                 "color": COLORS["rod"]}] if a is not None and b is not None and a != b else [])
        return [e for e in ends if e is not None] + rod

    def prismatic(self, comp, v):
        n = unit_vector(_get(v, "n", _X))
        name = f"{comp.name}.q"
        q = self.results[name] if name in self.results else np.zeros(1)
        lo, hi = min(q.min(), 0.0), max(q.max(), 0.0)
        w = self.L / 20
        return [_shape("box", self.frame(comp, "frame_a"), n * lo, n, hi - lo + 1e-9 * self.L,
                       w / 2, w / 2, COLORS["rod"]),
                _shape("box", self.frame(comp, "frame_b"), -n * self.L / 20, n, self.L / 10,
                       w, w, COLORS["joint"])]

    def planar(self, comp, v):
        n = unit_vector(_get(v, "n", _Z))
        s = self.L / 10
        return [_shape("box", self.frame(comp, "frame_a"), -n * s / 16, n, s / 8, s, s,
                       COLORS["joint"])]

    def rod(self, comp, v):
        a, b = self.frame(comp, "frame_a"), self.frame(comp, "frame_b")
        if a is None or b is None or a == b or ("r" in v and not np.any(v["r"])):
            return []
        return [{"kind": "rod", "frame": a, "to": b, "diameter": self.L / 40,
                 "color": COLORS["rod"]}]

    def line_force(self, comp, v):
        a, b = self.frame(comp, "frame_a"), self.frame(comp, "frame_b")
        if "c" not in v:
            return [{"kind": "rod", "frame": a, "to": b, "diameter": self.L / 25,
                     "color": COLORS["damper"]}]
        return [{"kind": "spring", "frame": a, "to": b, "diameter": self.L / 15,
                 "wire": self.L / 150, "windings": 8, "color": COLORS["spring"]}]

    def body(self, comp, v):
        k, cm = self.frame(comp, "frame_a"), self.bodies.get(comp.name)
        c = np.asarray(_get(v, "r_cm", np.zeros(3)), dtype=float)
        color = _color(_get(v, "color", None), COLORS["body"])
        kind = _get(v, "shape", None)
        if kind:
            size = np.asarray(_get(v, "shape_size", [self.L / 9] * 3), dtype=float)
            return [_shape(kind, k, c - _X * size[0] / 2, _X, *size, color)]
        m = float(_numbers(comp.bound(v).mass_properties()[0])[0])
        ratio = (m / self.heaviest) ** (1 / 3) if self.heaviest > 0 else 1.0
        d = self.L / 9 * max(ratio, 0.4)
        out = [_shape("sphere", cm, -_X * d / 2, _X, d, d, d, color)]
        if np.linalg.norm(c) > d / 2:
            out.append({"kind": "rod", "frame": k, "to": cm, "diameter": d / 5,
                        "color": color})
        return out

    def msl_body(self, comp, v, kind):
        """BodyBox and BodyCylinder as Modelica draws them."""
        r = np.asarray(_get(v, "r", np.zeros(3)), dtype=float)
        start = np.asarray(_get(v, "r_shape", np.zeros(3)), dtype=float)
        ld = unit_vector(_get(v, "length_direction", r - start), fallback=_X)
        length = float(_get(v, "length", np.linalg.norm(r - start)))
        width = float(_get(v, "width" if kind == "box" else "diameter", length / 20))
        height = float(_get(v, "height", width)) if kind == "box" else width
        wd = perpendicular(ld, _get(v, "width_direction", _Y))
        return [_shape(kind, self.frame(comp, "frame_a"), start, ld, length, width, height,
                       _color(_get(v, "color", None), COLORS["body"]), wd)]

    def wheel(self, comp, v):
        """A rolling wheel as a disk of its radius about the wheel axis (frame_b's y), a
        fifth of the radius thick."""
        r = float(_get(v, "radius", self.L / 10))
        return [_shape("cylinder", self.frame(comp, "frame_b"), -_Y * r / 10, _Y, r / 5,
                       2 * r, 2 * r, COLORS["body"])]

    def sphere_body(self, comp, v):
        d = float(_get(v, "diameter", self.L / 9))
        start = np.asarray(_get(v, "r_shape", np.zeros(3)), dtype=float)
        return [_shape("sphere", self.frame(comp, "frame_a"), start - _X * d / 2, _X, d, d, d,
                       _color(_get(v, "color", None), COLORS["body"]))]


def _get(values, key, default):
    value = values.get(key)
    return default if value is None else value


def unit_vector(v, fallback=_Z):
    """``v`` of length one, or ``fallback`` when it is zero."""
    v = np.asarray(v, dtype=float)
    norm = np.linalg.norm(v)
    return v / norm if norm > 0 else np.asarray(fallback, dtype=float)


def perpendicular(n, hint=_Y):
    """A unit vector orthogonal to the unit ``n``, as close to ``hint`` as can be."""
    for h in (np.asarray(hint, dtype=float), _Y, _X, _Z):
        w = h - np.dot(h, n) * n
        if np.linalg.norm(w) > 1e-6:
            return w / np.linalg.norm(w)
    return _Y


def _shape(kind, frame, r_shape, ld, length, width, height, color, wd=None):
    if kind not in ("box", "cylinder", "sphere") or frame is None:
        return None
    ld = unit_vector(ld, _X) + 0.0                  # + 0.0: no -0.0 in the data
    if kind != "box":                          # round: one diameter
        width = height = length if kind == "sphere" else width
    return {"kind": kind, "frame": frame, "r_shape": (np.asarray(r_shape, float) + 0.0).tolist(),
            "length_direction": ld.tolist(),
            "width_direction": (perpendicular(ld, _Y if wd is None else wd) + 0.0).tolist(),
            "length": float(length), "width": float(width), "height": float(height),
            "color": color}


def _axes(frame, length):
    return {"kind": "axes", "frame": frame, "length": float(length), "component": None,
            "color": "#000000"}


def _color(value, default):
    if value is None:
        return default
    if isinstance(value, str):
        return value if value.startswith("#") and len(value) == 7 else default
    rgb = np.clip(np.asarray(value, dtype=float).ravel()[:3], 0, 255)
    if rgb.max() <= 1:
        rgb = rgb * 255
    return "#" + "".join(f"{int(round(c)):02x}" for c in rgb)


#: type name -> how it looks; a subclass looks like its nearest registered ancestor
VISUALS = {
    "multibody.Revolute": Scene.joint,
    "multibody.Cylindrical": lambda s, c, v: s.joint(c, v, axis="axis"),
    "multibody.Prismatic": Scene.prismatic,
    "multibody.Spherical": Scene.ball,
    "multibody.Universal": Scene.ball,
    "multibody.SphericalSpherical": Scene.rod_joint,
    "multibody.UniversalSpherical": Scene.rod_joint,
    "multibody.Planar": Scene.planar,
    "multibody.FreeMotion": lambda scene, comp, values: [],     # no joint to see: a body flies
    "multibody.RollingWheelJoint": Scene.wheel,
    "multibody.FixedTranslation": Scene.rod,
    "multibody.FixedRotation": Scene.rod,
    "multibody.RigidBody": Scene.body,
    "multibody.BodyBox": lambda s, c, v: s.msl_body(c, v, "box"),
    "multibody.BodyCylinder": lambda s, c, v: s.msl_body(c, v, "cylinder"),
    "multibody.BodySphere": Scene.sphere_body,
    "multibody.PointMass": lambda s, c, v: s.sphere_body(c, {"diameter": v.get("sphereDiameter"),
                                                             "color": v.get("color")}),
    "multibody.SpringDamper": Scene.line_force,
    "multibody.Spring": Scene.line_force,
    "multibody.Damper": Scene.line_force,
}


def _visual(comp):
    for klass in type(comp).__mro__:
        draw = VISUALS.get(vars(klass).get("type_name"))
        if draw is not None:
            return draw
    if hasattr(type(comp), "mass_properties") and "frame_a" in comp.ports:
        return Scene.body                   # an unknown body: a sphere at its centre
    if comp.role == "joint":
        return Scene.ball
    if comp.role == "part":
        return Scene.rod
    return None

