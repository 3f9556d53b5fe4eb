"""Declaration machinery: a component is a class of ``Port`` and ``Param`` declarations.

Ports and parameters are collected from the class body in order, so documentation, the file
format and validation are all generated from the same declarations and never drift. This
module holds ports, the registry and ``Component``; parameters (``Param``) are in
``params.py``.
"""

import copy
import inspect

from ..errors import ModelError, Problem
from ..util import hint, quote, suggest
# the declarations' constants and Param are imported from here by the other libraries, the
# graph and the faces, as before Param moved to params.py
from .params import (ANY, COLOR, COORDINATES, DOMAINS, NAME_LIMIT, ONED,  # noqa: F401
                     RATES, REQUIRED, TABLE_ROWS_LIMIT, _NAME, Param)
from .reference import docstring, signature


#: type name ("multibody.Revolute") -> class; files resolve types only through this table.
REGISTRY = {}


class Port:
    """A connector of one physical domain."""

    def __init__(self, domain, doc="", optional=False):
        if domain not in DOMAINS + (ONED, ANY):
            raise ValueError(f"unknown domain {domain!r}")
        self.domain, self.doc, self.optional = domain, doc, optional
        self.name = None

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, instance, owner):
        return self if instance is None else PortRef(instance, self.name)

    def __set__(self, instance, value):
        also = [key for key, spec in instance.params.items() if self.name in spec.aliases]
        where = (f"; the parameter of that name in files is {instance.name}.{also[0]}"
                 if also else "")
        raise ModelError(f"{instance.name}.{self.name} is a port, not a parameter: wire it with "
                         f"model.connect{where}", component=instance.name, port=self.name)


class PortRef:
    """One port of one component instance, as passed to ``Model.connect``."""

    __slots__ = ("component", "name")

    def __init__(self, component, name):
        self.component, self.name = component, name

    @property
    def domain(self):
        return self.component.ports[self.name].domain

    @property
    def path(self):
        return f"{self.component.name}.{self.name}"

    def __eq__(self, other):
        return (isinstance(other, PortRef) and other.component is self.component
                and other.name == self.name)

    def __hash__(self):
        return hash((id(self.component), self.name))

    def __repr__(self):
        return f"<port {self.path} ({self.domain})>"


#: what other tools (Modelica's MSL, Simscape, MapleSim) call a component kinetwork has under
#: another name, looked up by the name after the library
#: what other tools call a kinetwork type: a name, or "lib.Name" where the library decides
#: (MSL's MultiBody ``Fixed`` is a fixed frame, its Rotational ``Fixed`` a fixed flange)
ELSEWHERE = {"World": ["multibody.Ground"], "Body": ["multibody.RigidBody"],
             "RigidTransform": ["multibody.FixedRotation"],
             "Translation": ["multibody.FixedTranslation"],
             "Rotation": ["multibody.FixedRotation"], "RevoluteJoint": ["multibody.Revolute"],
             "PrismaticJoint": ["multibody.Prismatic"], "SphericalJoint": ["multibody.Spherical"],
             "Gear": ["rotational.IdealGear"], "Motor": ["electrical.DCMotor"],
             "Capacitance": ["electrical.Capacitor"], "Inductance": ["electrical.Inductor"],
             "Resistance": ["electrical.Resistor"], "Source": ["signals.Constant"],
             "PointGravity": ["multibody.Ground"], "Fixed": ["multibody.Ground"],
             "multibody.Fixed": ["multibody.Ground"],
             "rotational.Ground": ["rotational.Fixed"],
             "translational.Ground": ["translational.Fixed"],
             "multibody.Mass": ["multibody.PointMass", "translational.Mass"],
             "multibody.Inertia": ["multibody.RigidBody", "rotational.Inertia"],
             "ConstantTorque": ["rotational.Torque"], "TorqueSource": ["rotational.Torque"],
             "ForceSource": ["translational.Force"], "ConstantForce": ["translational.Force"],
             "ConstantVoltage": ["electrical.VoltageSource"],
             "SineVoltage": ["electrical.VoltageSource"],
             "StepVoltage": ["electrical.VoltageSource"],
             "ConstantCurrent": ["electrical.CurrentSource"],
             "LimPID": ["signals.PID"], "PI": ["signals.PID"], "Feedback": ["signals.Add"],
             "Sensor": ["Probe"], "PositionSensor": ["translational.PositionSensor"]}


def type_suggestions(kind):
    """The types the unknown component type ``kind`` ("lib.Name") may stand for, best first:
    what other tools call it (``multibody.World``: multibody.Ground), the same name in the
    other libraries (``rotational.Mass``: translational.Mass), else the closest names."""
    name = str(kind).rpartition(".")[2]
    found = [k for k in ELSEWHERE.get(str(kind), []) + ELSEWHERE.get(name, [])
             if k in REGISTRY and k != kind]
    found += sorted(k for k in REGISTRY if k.rpartition(".")[2].lower() == name.lower()
                    and k != kind)
    found = list(dict.fromkeys(found))
    if not found:
        import difflib                  # here: the command line starts without it
        found = difflib.get_close_matches(str(kind)[:100], list(REGISTRY), n=1)
    return found[:3]


def type_suggestion(kind):
    """' (did you mean ...?)' for the unknown component type ``kind`` (see
    ``type_suggestions``); '' if none."""
    found = type_suggestions(kind)
    return f" (did you mean {' or '.join(repr(k) for k in found)}?)" if found else ""


class NoSuchComponent(AttributeError):
    """``kn.multibody.World``: no such component type in that library. An AttributeError
    (``hasattr`` and ``getattr`` with a default keep working) whose message says what it may
    be, across libraries; ``library``, ``name`` and ``suggestions`` hold the same as data."""

    def __init__(self, library, name):
        self.library, self.name = library, name
        self.suggestions = type_suggestions(f"{library}.{name}")
        close = f" (did you mean {' or '.join(repr(k) for k in self.suggestions)}?)" \
            if self.suggestions else ""
        super().__init__(f"kinetwork.{library} has no component {quote(name)}{close}")


def library_attribute(library):
    """The ``__getattr__`` of a library's module: an unknown component is a
    ``NoSuchComponent`` that says what it may be (``kn.multibody.World``: did you mean
    'multibody.Ground'?)."""
    def __getattr__(name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise NoSuchComponent(library, name)
    return __getattr__


class NoSuchAttribute(ModelError, AttributeError):
    """A component's misspelt port or parameter: a ModelError for the user, and an
    AttributeError for Python's protocol (``hasattr``, ``getattr`` with a default), so that
    asking whether a component has something never raises."""


def _cut(key):
    """A parameter key as given, cut for messages (a file may hold any text as a key)."""
    return key if isinstance(key, str) and len(key) <= NAME_LIMIT else quote(key, NAME_LIMIT)


class Component:
    """Base of every component: a name, declared ports and declared parameters."""

    #: library path used in files, e.g. "multibody.Revolute"; set by ``library=`` on subclasses
    type_name = None
    ports = {}
    params = {}
    #: what the component is to the solver: world, joint, body, compliant, source, fixed, probe
    role = None
    #: the class's docstring as written (``__doc__`` is generated from the declarations)
    _own_doc = ""
    #: 1-D ports whose position is a joint coordinate (port -> coordinate index) or zero
    coordinate_ports = {}
    zero_ports = ()
    #: another name a parameter is given by -> its name (``Param(aliases=...)``)
    aliases = {}
    #: parameter -> the alias it was given by, kept for the file it is saved to
    _spelling = {}
    #: groups of signal ports that carry signals of one unit (an Add's inputs and output, a
    #: PID's set point and measurement): how units spread along signal wires to the plots
    same_unit_ports = ()

    def signal_unit(self, port):
        """The unit of the signal at signal port ``port`` when this component fixes it (an
        angle sensor's output: "rad"; a torque source's input: "N*m"), else None."""
        return None

    def __init_subclass__(cls, library=None, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.ports = {}
        cls.params = {}
        cls.aliases = {}
        for klass in reversed(cls.__mro__):
            for key, val in vars(klass).items():
                if isinstance(val, Port):
                    if val.domain == ONED and getattr(cls, "domain", None):
                        val = copy.copy(val)
                        val.domain = cls.domain
                    cls.ports[key] = val
                elif isinstance(val, Param):
                    cls.params[val.name] = val.resolved(cls)
        cls.aliases = {alias: key for key, spec in cls.params.items() for alias in spec.aliases}
        # a subclass declared without ``library=`` is not a file type (not its parent's either)
        cls.type_name = None
        cls._own_doc = inspect.cleandoc(vars(cls).get("__doc__") or "") or cls._own_doc
        if library is not None and not cls.__name__.startswith("Partial"):
            cls.type_name = f"{library}.{cls.__name__}" if library else cls.__name__
            REGISTRY[cls.type_name] = cls
            # help(), IDEs and the docs read what the declarations say
            cls.__signature__ = signature(cls)
            cls.__doc__ = docstring(cls)

    def __init__(self, name, **params):
        self._declare(name, params, None)

    @classmethod
    def from_params(cls, name, params, place=None):
        """Build from a dict of parameters, as a file gives them (any key, even "name").

        ``place(key)`` locates a parameter in messages (files pass their JSON path).
        """
        comp = cls.__new__(cls)
        comp._declare(name, params, place)
        return comp

    def _declare(self, name, params, place):
        place = place or (lambda key: f"{name}.{_cut(key)}")
        if not isinstance(name, str) or not _NAME.fullmatch(name):
            size = (f"; at most {NAME_LIMIT} characters, got {len(name)}"
                    if isinstance(name, str) and len(name) > NAME_LIMIT else "")
            raise ModelError(f"{type(self).__name__} name {quote(name)}: must be an identifier "
                             f"(letters, digits, underscore; not starting with a digit{size})")
        object.__setattr__(self, "name", name)
        kind = self.type_name or type(self).__name__
        problems = [Problem(f"{place(key)}: unknown parameter{close}; {kind} has "
                            f"{self._listed()}", component=name, parameter=_cut(key),
                            hint=hint(close))
                    for key in params if key not in self.params and key not in self.aliases
                    for close in [suggest(key, [*self.params, *self.aliases])]]
        object.__setattr__(self, "_spelling", {})
        for alias, key in self.aliases.items():
            if alias in params and key in params:
                problems.append(Problem(f"{place(alias)}: {alias} and {key} are one "
                                        f"parameter; give {key} alone", component=name,
                                        parameter=alias, hint=f"remove {alias}"))
            elif alias in params:
                params = {key if k == alias else k: v for k, v in params.items()}
                self._spelling[key] = alias
        object.__setattr__(self, "given", {})
        object.__setattr__(self, "_values", {})
        for key, spec in self.params.items():
            written = self._spelling.get(key, key)
            try:
                if key in params:
                    self.given[key] = spec.normalize(params[key], place(written))
                    self._values[key] = spec.si(self.given[key])
                elif spec.required:
                    problems.append(Problem(f"{place(key)}: a value is required "
                                            f"({spec.describe()})", parameter=key))
                else:
                    self._values[key] = spec.si(spec.normalize(spec.default, place(key)))
            except ModelError as exc:
                problems.extend(p.where(parameter=written) for p in exc.problems)
        if problems:
            raise ModelError(problems, component=name)

    def _listed(self):
        """The parameters, each with its other names: "cut, n (or axis), q0"."""
        also = {key: [a for a, k in self.aliases.items() if k == key] for key in self.params}
        return ", ".join(f"{key} (or {', '.join(also[key])})" if also[key] else key
                         for key in self.params) or "none"

    def check_values(self, values, place):
        """Problems of the evaluated parameters ``values`` taken together (a hole no wider than
        its body), as messages naming ``place(key)``; the validation calls it. None here."""
        return []

    def required_ports(self):
        """Optional ports that this instance's parameters make required (a force resolved in
        the frame wired to its frame_resolve); none here."""
        return ()

    def set_param(self, key, value):
        """Change parameter ``key`` (its file name) to ``value``, checked as at construction.

        The new value is what ``Model.save``, ``numeric_values`` and ``simulate`` see; a
        compiled System of a model holding this component is rebuilt on its next use.
        """
        if key in self.aliases:
            self._spelling = {**self._spelling, self.aliases[key]: key}
            key = self.aliases[key]
        elif key not in self.params:
            close = suggest(key, self.params)
            raise ModelError(f"{type(self).__name__} {self.name!r} has no parameter "
                             f"{quote(key)}{close}; parameters: {self._listed()}",
                             component=self.name, hint=hint(close),
                             parameter=_cut(key) if isinstance(key, str) else None)
        elif key in self._spelling:
            self._spelling = {k: v for k, v in self._spelling.items() if k != key}
        try:
            value = self.params[key].normalize(value, f"{self.name}.{key}")
        except ModelError as exc:
            raise ModelError(exc.problems, component=self.name, parameter=key) from None
        self.given[key] = value
        self._values[key] = self.params[key].si(value)

    def written_params(self):
        """The given parameters as a file holds them: each by the name it was given by (a
        joint's ``n`` given as ``axis`` is saved as ``axis``)."""
        return {self._spelling.get(key, key): copy.deepcopy(value)
                for key, value in self.given.items()}

    def __setattr__(self, key, value):
        declared = getattr(type(self), key, None)
        if isinstance(declared, (Param, Port)) or key.startswith("_"):
            object.__setattr__(self, key, value)
            return
        if key == "name":
            raise ModelError(f"{self.name!r}: a component cannot be renamed; build a new one "
                             f"(a model refers to its components by name)",
                             component=self.name)
        if key in self.params or key in self.aliases:     # a subsystem's, or another name
            self.set_param(key, value)
            return
        close = suggest(key, [*self.params, *self.ports])
        raise ModelError(f"{type(self).__name__} {self.name!r} has no parameter "
                         f"{quote(key)}{close}; change a parameter with comp.<parameter> = "
                         f"value or comp.set_param(name, value); parameters: "
                         f"{self._listed()}", component=self.name, hint=hint(close))

    def __delattr__(self, key):
        raise ModelError(f"{self.name}.{key}: parameters and ports cannot be deleted",
                         component=self.name)

    def __getattr__(self, key):
        # reached only when normal lookup fails: a misspelt port or parameter
        if key.startswith("_"):
            raise AttributeError(key)
        close = suggest(key, [*self.ports, *self.params])
        raise NoSuchAttribute(f"{type(self).__name__} {self.name!r} has no port or parameter "
                              f"{key!r}{close}; ports: {', '.join(self.ports)}",
                              component=self.name, hint=hint(close))

    def port_ref(self, name):
        """The ``PortRef`` called ``name``; a ModelError suggesting close names otherwise."""
        if name not in self.ports:
            close = suggest(name, self.ports)
            raise ModelError(f"{type(self).__name__} {self.name!r} has no port {quote(name)}"
                             f"{close}; ports: {', '.join(self.ports)}", component=self.name,
                             port=_cut(name) if isinstance(name, str) else None,
                             hint=hint(close))
        return PortRef(self, name)

    def bound(self, values):
        """A copy whose parameters read as ``values`` (numbers or CasADi symbols)."""
        twin = copy.copy(self)
        object.__setattr__(twin, "_values", dict(values))
        return twin

    def __repr__(self):
        return f"<{self.type_name} {self.name!r}>"
