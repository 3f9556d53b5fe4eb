"""Bodies of the multibody library, as Modelica's MultiBody.Parts: RigidBody (mass, centre
of mass, inertia), BodyShape (a body hanging from either end of a rigid part), and the bodies
whose mass properties follow from their geometry and density (BodyBox, BodyCylinder,
BodySphere). A body with a shape is a rigid part that is also a body on its frame_a: its
transform is a FixedTranslation's. Part of ``kn.multibody``.
"""

import math

import numpy as np

from ..errors import ModelError
from ..spatial import eye3, mat3, unit, vec3
from .base import Component, Param, Port
from .frames import PartialRigidTransform

MB = "multibody"


#: MSL's world.defaultWidthFraction: a shape's default width (or diameter) is its length / 20
WIDTH_FRACTION = 20
#: what RigidBody's ``shape`` may draw
SHAPES = ("box", "cylinder", "sphere")


def _color():
    return Param(None, optional=True, kind="color",
                 doc="Colour in the animation, '#rrggbb' (None: the animation's default)")


def _density():
    return Param(7700.0, unit="kg/m^3", min=0.0,
                 doc="Density (steel 7700 to 7900, aluminium 2700, wood 400 to 800)")


def _numbers(value):
    """``value`` with its numbers as floats (lists of them), or None when it holds an
    expression: sizes are compared once every one of them is known."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, list):
        items = [_numbers(v) for v in value]
        return None if any(v is None for v in items) else items
    if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
        return float(value)
    return None


def _direction(n, fallback):
    """``n`` made a unit vector, or ``fallback`` when it is (nearly) zero, as MSL's
    Frames.from_nxy does (CasADi's if_else: it works on symbols as on numbers)."""
    import casadi as ca
    size = ca.norm_2(n)
    return ca.if_else(size < 1e-10, ca.DM(fallback), n / size)


def _axes(n_x, n_y):
    """Columns e_x, e_y, e_z of the frame whose x axis is along ``n_x`` and whose x-y plane
    holds ``n_y``: MSL's Frames.from_nxy (transposed: MSL returns the rows), robust as it is
    to a zero n_x and to an n_y parallel to n_x."""
    import casadi as ca
    ex = _direction(n_x, [1.0, 0.0, 0.0])
    ey = _direction(n_y, [0.0, 1.0, 0.0])
    nz = ca.cross(ex, ey)
    ey = ca.if_else(ca.dot(nz, nz) > 1e-6, ey,
                    ca.if_else(ca.fabs(ex[0]) > 1e-6, ca.DM([0.0, 1.0, 0.0]),
                               ca.DM([1.0, 0.0, 0.0])))
    ez = unit(ca.cross(ex, ey))
    return ca.horzcat(ex, ca.cross(ez, ex), ez)


class _CheckedTogether:
    """Parameters that are checked together as well as one by one (a hole no wider than its
    body): numbers at construction and assignment, expressions once the model's parameters
    give them values (``check_values``, called by the validation)."""

    def check_values(self, values, place):
        """Problems of the evaluated parameters ``values`` taken together, as messages naming
        their place (``place(key)``); none while one of them is an expression."""
        return []

    def _declare(self, name, params, place):
        super()._declare(name, params, place)
        problems = self.check_values(self._values, place or (lambda key: f"{name}.{key}"))
        if problems:
            raise ModelError(problems)

    def set_param(self, key, value):
        given, values = dict(self.given), dict(self._values)
        super().set_param(key, value)
        problems = self.check_values(self._values, lambda k: f"{self.name}.{k}")
        if problems:              # refused: the component is left as it was
            self.given.clear()
            self.given.update(given)
            self._values.clear()
            self._values.update(values)
            raise ModelError(problems)

    def _known(self, values):
        """The real parameters of ``values`` as numbers, or None while one is an expression."""
        known = {}
        for key, value in values.items():
            if self.params[key].kind != "real":
                known[key] = value
            elif value is None:
                known[key] = None
            else:
                known[key] = _numbers(value)
                if known[key] is None:
                    return None
        return known


class RigidBody(_CheckedTogether, Component, library=MB):
    """Mass and inertia attached to frame_a.

    ``shape``, ``shape_size`` and ``color`` are looks only: they tell the animation what to
    draw and change nothing in the physics.

    Parameters
    ----------
    mass : kg, >= 0, required
        Mass.
    r_cm : m, 3 values, default [0, 0, 0]
        Centre of mass from frame_a, resolved in frame_a.
    inertia : kg*m^2, 3x3 or its diagonal, default zero
        Inertia about the centre of mass, in frame_a axes.
    shape : "box", "cylinder", "sphere" or None, default None
        What the animation draws, centred at r_cm (None: a small sphere).
    shape_size : m, 3 values >= 0, default None
        Size of the shape: a box's extents along frame_a's x, y, z; a cylinder's length
        (along frame_a's x) and diameter, the third unused; a sphere's diameter, the other two
        unused.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    role = "body"
    frame_a = Port("frame", "Frame the body is fixed to")
    mass = Param(unit="kg", min=0.0, doc="Mass")
    r_cm = Param([0.0, 0.0, 0.0], unit="m", shape=(3,),
                 doc="Centre of mass from frame_a, resolved in frame_a")
    inertia = Param([[0.0] * 3] * 3, unit="kg*m^2", shape=(3, 3),
                    doc="Inertia about the centre of mass, in frame_a axes (3x3 or diagonal)")
    shape = Param(None, optional=True, kind="choice", choices=SHAPES,
                  doc="What the animation draws at r_cm (None: a small sphere); looks only")
    shape_size = Param(None, optional=True, unit="m", shape=(3,),
                       doc="Box: extents along x, y, z of frame_a; cylinder: length along x, "
                           "diameter; sphere: diameter; looks only")
    color = _color()

    def mass_properties(self):
        """(mass, centre of mass, inertia about it) as CasADi values."""
        return self.mass, vec3(self.r_cm), mat3(self.inertia)

    def check_values(self, values, place):
        size = values.get("shape_size")
        size = [] if size is None else list(size)
        return [f"{place('shape_size')}[{i}] = {v} m: must be >= 0"
                for i, v in enumerate(size) if _numbers(v) is not None and v < 0]


class BodyShape(_CheckedTogether, PartialRigidTransform, library=MB):
    """A rigid body between two frames (MSL's Parts.BodyShape): frame_b is frame_a moved by
    ``r`` (a FixedTranslation), and the mass, centre of mass and inertia are given as a
    RigidBody's on frame_a. A rigid part with mass: it folds into the body before it and
    costs no state, so it hangs from either end alike.

    ``shape``, ``shape_size`` and ``color`` are looks only (MSL's shapeType, length and
    width, color): what an animation draws from frame_a towards frame_b.

    Parameters
    ----------
    r : m, 3 values, required
        Position of frame_b in frame_a.
    mass : kg, >= 0, required
        Mass.
    r_cm : m, 3 values, default [0, 0, 0]
        Centre of mass from frame_a, resolved in frame_a.
    inertia : kg*m^2, 3x3 or its diagonal, default zero
        Inertia about the centre of mass, in frame_a axes.
    shape : "box", "cylinder", "sphere", default "cylinder"
        What the animation draws from frame_a along r; looks only.
    shape_size : m, 3 values >= 0, default None
        Length, width and height of the shape (None: |r|, |r| / 20, |r| / 20); looks only.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    has_mass = True
    frame_a = Port("frame", "Frame a, the body's own (may be left unwired when the body hangs "
                            "from frame_b)", optional=True)
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    mass = RigidBody.params["mass"]
    r_cm = RigidBody.params["r_cm"]
    inertia = RigidBody.params["inertia"]
    shape = Param("cylinder", kind="choice", choices=SHAPES,
                  doc="What the animation draws from frame_a along r; looks only")
    shape_size = Param(None, optional=True, unit="m", shape=(3,),
                       doc="Length, width, height of the shape (None: |r|, |r|/20, |r|/20); "
                           "looks only")
    color = _color()

    def transform(self, q):
        return eye3(), vec3(self.r)

    mass_properties = RigidBody.mass_properties
    check_values = RigidBody.check_values


class PartialBodyShape(_CheckedTogether, PartialRigidTransform):
    """A solid between two frames: frame_b is frame_a moved by ``r`` (a FixedTranslation),
    and the solid's mass, centre of mass and inertia sit on frame_a (a RigidBody) as MSL's
    Parts.BodyBox and BodyCylinder compute them. A rigid part with mass: it folds into the
    body before it and costs no state.

    The solid starts at ``r_shape`` and extends ``length`` along ``length_direction``; its
    inertia is resolved along these axes of the shape. (MSL's BodyBox and BodyCylinder
    resolve it along ``r`` instead, which differs only when the length direction is not that
    of ``r``: there MSL's inertia is not that of the solid it draws.)
    """
    has_mass = True
    frame_a = Port("frame", "Frame a, the body's own (may be left unwired when the body hangs "
                            "from frame_b)", optional=True)
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    r_shape = Param([0.0, 0.0, 0.0], unit="m", shape=(3,),
                    doc="Start of the shape from frame_a, resolved in frame_a")
    length_direction = Param(None, optional=True, unit="1", shape=(3,), nonzero=True,
                             doc="Direction of the length, in frame_a (None: r - r_shape)")
    length = Param(None, optional=True, unit="m", min=0.0,
                   doc="Length (None: |r - r_shape|)")

    def transform(self, q):
        return eye3(), vec3(self.r)

    def _length(self):
        import casadi as ca
        if self.length is not None:
            return self.length
        return ca.norm_2(vec3(self.r) - vec3(self.r_shape))

    def _length_axis(self):
        """The length direction as given (not yet of length one)."""
        if self.length_direction is None:
            return vec3(self.r) - vec3(self.r_shape)
        return vec3(self.length_direction)

    def check_values(self, values, place):
        import casadi as ca
        known = self._known(values)
        if known is None:
            return []
        sizes = {k: float(ca.DM(v)) for k, v in self.bound(known).sizes().items()}
        # a pair both left to their defaults (a box's inner_height and height) repeats the
        # pair they follow: it is not reported twice
        return [f"{place(inner)} = {sizes[inner]:.6g} m: must be <= {outer} "
                f"({sizes[outer]:.6g} m)" for inner, outer in self.holes
                if sizes[inner] > sizes[outer]
                and not (known[inner] is None and known[outer] is None)]


class BodyBox(PartialBodyShape, library=MB):
    """A box between frame_a and frame_b, solid or hollow, its mass from its density (MSL's
    Parts.BodyBox).

    frame_b is frame_a moved by ``r``. The box starts at ``r_shape`` and runs ``length``
    along ``length_direction``; ``width`` is measured along ``width_direction`` made
    orthogonal to it and ``height`` along the third axis. A hollow box (``inner_width`` > 0)
    has a hole of ``inner_width`` by ``inner_height`` along its whole length.

    Mass and inertia, as MSL: mo = density*length*width*height, mi =
    density*length*inner_width*inner_height, m = mo - mi, centre of mass r_shape +
    length/2 along the length, and about it, along the box's axes,
    diag(mo*(w^2 + h^2) - mi*(wi^2 + hi^2), mo*(l^2 + h^2) - mi*(l^2 + hi^2),
    mo*(l^2 + w^2) - mi*(l^2 + wi^2)) / 12, resolved in frame_a.

    Parameters
    ----------
    r : m, 3 values, required
        Position of frame_b in frame_a.
    r_shape : m, 3 values, default [0, 0, 0]
        Where the box starts, from frame_a, resolved in frame_a.
    length_direction : 3 values, not zero, default None
        Direction of the length, in frame_a (None: r - r_shape).
    length : m, >= 0, default None
        Length of the box (None: |r - r_shape|).
    width_direction : 3 values, not zero, default [0, 1, 0]
        Direction of the width, in frame_a; its part orthogonal to the length is used.
    width : m, >= 0, default None
        Width (None: length / 20, MSL's world.defaultWidthFraction).
    height : m, >= 0, default None
        Height (None: the width).
    inner_width : m, >= 0 and <= width, default 0
        Width of the hole (0: a solid box).
    inner_height : m, >= 0 and <= height, default None
        Height of the hole (None: inner_width).
    density : kg/m^3, >= 0, default 7700
        Density of the material.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    holes = (("inner_width", "width"), ("inner_height", "height"))
    width_direction = Param([0.0, 1.0, 0.0], unit="1", shape=(3,), nonzero=True,
                            doc="Direction of the width, in frame_a (made orthogonal to the "
                                "length)")
    width = Param(None, optional=True, unit="m", min=0.0,
                  doc="Width (None: length / 20)")
    height = Param(None, optional=True, unit="m", min=0.0, doc="Height (None: width)")
    inner_width = Param(0.0, unit="m", min=0.0, doc="Width of the hole (0: solid)")
    inner_height = Param(None, optional=True, unit="m", min=0.0,
                         doc="Height of the hole (None: inner_width)")
    density = _density()
    color = _color()

    def sizes(self):
        """Length, width, height and those of the hole, defaults filled in."""
        length = self._length()
        width = length / WIDTH_FRACTION if self.width is None else self.width
        height = width if self.height is None else self.height
        inner_height = self.inner_width if self.inner_height is None else self.inner_height
        return {"length": length, "width": width, "height": height,
                "inner_width": self.inner_width, "inner_height": inner_height}

    def mass_properties(self):
        """(mass, centre of mass, inertia about it, in frame_a axes) as CasADi values."""
        import casadi as ca
        s = self.sizes()
        ln, w, h, wi, hi = (s[k] for k in ("length", "width", "height", "inner_width",
                                           "inner_height"))
        mo = self.density * ln * w * h
        mi = self.density * ln * wi * hi
        axes = _axes(self._length_axis(), vec3(self.width_direction))
        moments = ca.vertcat(mo * (w**2 + h**2) - mi * (wi**2 + hi**2),
                             mo * (ln**2 + h**2) - mi * (ln**2 + hi**2),
                             mo * (ln**2 + w**2) - mi * (ln**2 + wi**2)) / 12
        centre = vec3(self.r_shape) + axes[:, 0] * ln / 2
        return mo - mi, centre, axes @ ca.diag(moments) @ axes.T


class BodyCylinder(PartialBodyShape, library=MB):
    """A cylinder between frame_a and frame_b, solid or a tube, its mass from its density
    (MSL's Parts.BodyCylinder).

    frame_b is frame_a moved by ``r``. The cylinder starts at ``r_shape`` and runs
    ``length`` along ``length_direction``.

    Mass and inertia, as MSL, with R = diameter/2 and Ri = inner_diameter/2: mo =
    density*pi*length*R^2, mi = density*pi*length*Ri^2, m = mo - mi, centre of mass r_shape +
    length/2 along the axis; about it, (mo*R^2 - mi*Ri^2)/2 about the axis and
    (mo*(l^2 + 3*R^2) - mi*(l^2 + 3*Ri^2))/12 about any line across it.

    Parameters
    ----------
    r : m, 3 values, required
        Position of frame_b in frame_a.
    r_shape : m, 3 values, default [0, 0, 0]
        Where the cylinder starts, from frame_a, resolved in frame_a.
    length_direction : 3 values, not zero, default None
        Direction of the axis, in frame_a (None: r - r_shape).
    length : m, >= 0, default None
        Length of the cylinder (None: |r - r_shape|).
    diameter : m, >= 0, default None
        Outer diameter (None: length / 20, MSL's world.defaultWidthFraction).
    inner_diameter : m, >= 0 and <= diameter, default 0
        Inner diameter (0: a solid cylinder).
    density : kg/m^3, >= 0, default 7700
        Density of the material.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    holes = (("inner_diameter", "diameter"),)
    diameter = Param(None, optional=True, unit="m", min=0.0,
                     doc="Diameter (None: length / 20)")
    inner_diameter = Param(0.0, unit="m", min=0.0, doc="Inner diameter (0: solid)")
    density = _density()
    color = _color()

    def sizes(self):
        """Length, diameter and inner diameter, defaults filled in."""
        length = self._length()
        diameter = length / WIDTH_FRACTION if self.diameter is None else self.diameter
        return {"length": length, "diameter": diameter,
                "inner_diameter": self.inner_diameter}

    def mass_properties(self):
        """(mass, centre of mass, inertia about it, in frame_a axes) as CasADi values."""
        import casadi as ca
        s = self.sizes()
        ln, ro, ri = s["length"], s["diameter"] / 2, s["inner_diameter"] / 2
        mo = self.density * math.pi * ln * ro**2
        mi = self.density * math.pi * ln * ri**2
        along = (mo * ro**2 - mi * ri**2) / 2
        across = (mo * (ln**2 + 3 * ro**2) - mi * (ln**2 + 3 * ri**2)) / 12
        e = _direction(self._length_axis(), [1.0, 0.0, 0.0])
        # diag(along, across, across) in any axes whose x is e: only e matters
        inertia = across * ca.DM.eye(3) + (along - across) * (e @ e.T)
        return mo - mi, vec3(self.r_shape) + e * ln / 2, inertia


class BodySphere(Component, library=MB):
    """A solid sphere with frame_a at its centre, its mass from its density.

    m = density*pi*d^3/6, centre of mass at frame_a, inertia 2/5*m*(d/2)^2 about every axis.

    Parameters
    ----------
    diameter : m, >= 0, required
        Diameter.
    density : kg/m^3, >= 0, default 7700
        Density of the material.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    role = "body"
    frame_a = Port("frame", "Frame at the centre of the sphere")
    diameter = Param(unit="m", min=0.0, doc="Diameter")
    density = _density()
    color = _color()

    def mass_properties(self):
        """(mass, centre of mass, inertia about it) as CasADi values."""
        import casadi as ca
        mass = self.density * math.pi * self.diameter**3 / 6
        return mass, ca.DM.zeros(3), mass * self.diameter**2 / 10 * ca.DM.eye(3)
