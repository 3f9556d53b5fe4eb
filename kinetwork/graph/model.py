"""Model: the components, their wiring and the model parameters."""

from __future__ import annotations

import math
import os
import re
import threading
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from ..components.base import ANY, Component, PortRef
from ..util import hint, quote, suggest
from . import quantities
from .subsystem import (MAX_COMPONENTS, MAX_CONNECTIONS, Subsystem, check_placement,
                        check_port_name, definitions, flatten, has_subsystems, user_names)
from .writer import save
from ..errors import ModelError, Problem
from ..expr import CONSTANTS, FUNCTIONS, parse
from ..upcalls import upcall

if TYPE_CHECKING:       # annotations only: a model does not import what compiles it
    from ..equations.system import System
    from .topology import Topology

#: a component, as ``Model.add`` gives it back (its own class, for editors and type checkers)
C = TypeVar("C", bound=Component)

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,199}\Z")      # whole, as NAME_LIMIT in base.py
RESERVED = {"t", *CONSTANTS, *FUNCTIONS}
#: characters a model name may have; and what no name or description holds: control
#: characters (Unicode's Cc), lone surrogates (Cs: not text, no file can hold them), line and
#: paragraph separators (Zl, Zp). A regular expression: a description may be megabytes long
MODEL_NAME_LIMIT = 200
_NOT_TEXT = re.compile("[\x00-\x1f\x7f-\x9f\ud800-\udfff\u2028\u2029]")

_compile_lock = threading.RLock()


class Model:
    """A wiring diagram: components, connections between their ports, named parameters.

    Parameters
    ----------
    name : str
        Model name.
    parameters : dict, optional
        Model parameters (name -> number, or a number with a unit: ``"500 mm"``, kept in SI
        base units, checked against the units of the component parameters that use it, and
        saved as written; see ``kinetwork.graph.quantities``); component parameters may be
        expressions in them.
    description : str, optional
        Free text.
    simulation : dict, optional
        Experiment settings travelling with the model (t_end, n_points, method, rtol, atol,
        step).
    """

    def __init__(self, name: str, parameters: Mapping[str, float | str] | None = None,
                 description: str = "", simulation: Mapping[str, Any] | None = None):
        if (problem := model_name_problem(name)) is not None:
            raise ModelError(f"model name: {problem}")
        self.name = name
        self.description = description
        self.components = {}
        self.connections = []
        self._wired = set()            # the connections as unordered pairs, for O(1) checks
        self.parameters = {}
        #: name -> the quantity a parameter was given as ("500 mm"), its SI value in parameters
        self.parameter_text = {}
        self.simulation = dict(simulation or {})
        #: initial conditions as equations (``set_initial``; ``kinetwork.graph.initial``)
        self.initial = {}
        self.layout = {}
        #: ports this model shows when placed as a subsystem: name -> PortRef of a component
        self.exposed = {}
        #: subsystem definitions a file keeps with the model (name -> Model), used or not
        self.definitions = {}
        #: for a model read as a definition from a file: (real path, how it was found:
        #: "file", "folder" or "library", its text as read); a saver writes a reference to
        #: it while it is unchanged
        self.origin = None
        #: the file ``kn.load`` read this model from (absolute), or None
        self.path = None
        #: component name -> how messages locate it (files say 'components[3] "mass1"'; a
        #: flat model's inner components (path shown, place in their definition's file))
        self.places = {}
        #: component name -> the JSON path of its entry in the file the model was read from
        #: ("components[3]"); in a flat model, an inner component's is its subsystem's
        self.paths = {}
        self._validated = None         # (content key, parameter values, Topology)
        self._compiled = {}            # (content key, loops, rate) -> System
        self._flat = None              # (content key, flat model) of a model of subsystems
        self._source = None            # for a flat model: the model of subsystems it expands
        for key, value in (parameters or {}).items():
            self.set_parameter(key, value)

    def _init_flat(self, model):
        """Set up as the empty flat model of ``model`` (names by path, no checks: the
        flattening writes only what the inner models already checked)."""
        Model.__init__(self, model.name, description=model.description,
                       simulation=model.simulation)
        self.parameters = dict(model.parameters)
        self.initial = model.initial
        self._source = model

    # -- building -----------------------------------------------------------------------
    def set_parameter(self, name: str, value: float | str) -> None:
        """Add or change a model parameter: a number (SI) or a number with a unit (``"500 mm"``,
        converted to SI base units, saved as written). A path (``"cyl1.phi0"``) sets the value
        given to a parameter of a subsystem placed here (as ``model.components["cyl1"].phi0 =
        v``)."""
        if isinstance(name, str) and "." in name:
            instance, _, key = name.partition(".")
            comp = self.components.get(instance)
            if not isinstance(comp, Subsystem) or "." in key:
                # a value deeper down belongs to a definition that other instances share
                raise ModelError(f"parameter {quote(name, 60)}: a path names a parameter of a "
                                 f"subsystem placed in {self.name!r} ('instance.parameter'); "
                                 f"subsystems here: "
                                 f"{', '.join(c.name for c in self.components.values() if isinstance(c, Subsystem)) or 'none'}")
            comp.set_param(key, value)
            return
        if not isinstance(name, str) or not _IDENT.match(name):
            raise ModelError(f"parameter name {quote(name, 60)}: must be an identifier")
        if name in RESERVED:
            raise ModelError(f"parameter name {name!r} is reserved (time, constants, functions)")
        self.parameters[name] = quantities.to_si(value, f"parameters.{name}")
        if isinstance(value, str):
            self.parameter_text[name] = value
        else:
            self.parameter_text.pop(name, None)

    def written_parameters(self) -> dict[str, float | str]:
        """The model parameters as written: a quantity's text ("500 mm") while the number
        in ``parameters`` is still its value, else the number."""
        out = {}
        for name, value in self.parameters.items():
            text = self.parameter_text.get(name)
            try:
                same = text is not None and quantities.to_si(text, name) == value
            except ModelError:
                same = False
            out[name] = text if same else value
        return out

    def add(self, component: C) -> C:
        """Add ``component`` and return it."""
        if not isinstance(component, Component):
            raise ModelError(f"model.add expects a component, got {quote(component)}")
        if component.name in self.components:
            raise ModelError(f"duplicate component name {component.name!r}",
                             component=component.name)
        if len(self.components) >= MAX_COMPONENTS:
            raise ModelError(f"{component.name}: model {self.name!r} has {MAX_COMPONENTS} "
                             f"components already, the most a model may have",
                             component=component.name)
        if isinstance(component, Subsystem):
            check_placement(self, component)
        self.components[component.name] = component
        return component

    def set_initial(self, steady: bool = False, derivatives: Mapping[str, float] | None = None,
                    fixed: tuple[str, ...] | list[str] = (),
                    solve: tuple[str, ...] | list[str] = ()) -> None:
        """Ask for initial conditions as equations (see ``kinetwork.graph.initial``):
        ``steady`` (every derivative zero), ``derivatives`` ({state: value} at t = 0),
        ``fixed`` (states a steady state keeps) and ``solve`` (model parameters, or states
        without ``steady``, found from them): ``model.set_initial(steady=True,
        fixed=["rev.q"], solve=["c"])`` is MSL's InitSpringConstant. No arguments: the
        given start again."""
        from .initial import normalized
        self.initial = normalized({"steady": steady, "derivatives": dict(derivatives or {}),
                                   "fixed": list(fixed), "solve": list(solve)})

    def expose(self, name: str, port: PortRef | str) -> None:
        """Show ``port`` (``comp.port`` or ``"comp.port"``) as this model's port ``name``
        when it is placed as a subsystem: ``link.expose("frame_a", "joint.frame_a")``."""
        check_port_name(name)
        if name in self.exposed:
            raise ModelError(f"{self.name}: port {name!r} is already exposed (as "
                             f"{self.exposed[name].path})")
        try:
            self.exposed[name] = self.port(port)
        except ModelError as exc:
            raise ModelError([p.where(f"{self.name} port {name!r}: ")
                              for p in exc.problems]) from None

    def connect(self, a: PortRef | str, b: PortRef | str) -> None:
        """Wire two ports, given as ``comp.port`` attributes or ``"comp.port"`` strings."""
        pa, pb = self.port(a), self.port(b)
        if pa == pb:
            raise ModelError(f"cannot connect {pa.path} to itself")
        da, db = pa.domain, pb.domain
        signals = {da, db} <= {"signal_in", "signal_out"}
        if da != db and ANY not in (da, db) and not signals:
            raise ModelError(f"cannot connect {pa.path} ({da}) to {pb.path} ({db}): "
                             f"ports of different domains")
        if len(self._wired) != len(self.connections):     # the list was edited by hand
            self._wired = {frozenset(c) for c in self.connections}
        if frozenset((pa, pb)) in self._wired:
            raise ModelError(f"{pa.path} and {pb.path} are already connected")
        if len(self.connections) >= MAX_CONNECTIONS:
            raise ModelError(f"{pa.path} - {pb.path}: model {self.name!r} has "
                             f"{MAX_CONNECTIONS} connections already, the most a model may "
                             f"have")
        self.connections.append((pa, pb))
        self._wired.add(frozenset((pa, pb)))

    def port(self, ref: PortRef | str) -> PortRef:
        """Resolve a PortRef or a ``"comp.port"`` string to a PortRef of this model."""
        if isinstance(ref, PortRef):
            comp = self.components.get(ref.component.name)
            if comp is not ref.component:
                raise ModelError(f"{ref.path}: component {ref.component.name!r} is not in "
                                 f"model {self.name!r} (add it first)",
                                 hint=f"model.add({ref.component.name!r}) first")
            return ref
        if not isinstance(ref, str) or ref.count(".") != 1:
            raise ModelError(f"port reference {quote(ref)}: expected 'component.port'")
        cname, pname = ref.split(".")
        if cname not in self.components:
            close = suggest(cname, self.components)
            raise ModelError(f"{quote(ref)}: no component {quote(cname, 60)}{close}",
                             hint=hint(close))
        return self.components[cname].port_ref(pname)

    # -- checking -----------------------------------------------------------------------
    def place(self, component, key=None):
        """Where a component (and one of its parameters) is, for messages: its path in a flat
        model (``cyl3/piston.mass``, then where its definition's file has it), else its
        place in the file, else its name."""
        base = self.places.get(component.name)
        if isinstance(base, tuple):
            shown, where = base
            inner = f" ({where}{f' params.{key}' if key else ''})" if where else ""
            return f"{shown}.{key}{inner}" if key else f"{shown}{inner}"
        if base is None:
            return f"{component.name}.{key}" if key else component.name
        return f"{base} params.{key}" if key else base

    def problem(self, text, component=None, key=None, port=None, hint=None,
                severity="error"):
        """A Problem about ``component`` (its parameter ``key``, or its port ``port``): the
        message ``text`` after its place (``place``), its fields set (``fields``)."""
        if component is None:
            return Problem(text, hint=hint, severity=severity)
        return Problem(f"{self.place(component, key)}: {text}", hint=hint, severity=severity,
                       **self.fields(component, key, port))

    def fields(self, component, key=None, port=None):
        """The fields of a Problem about ``component`` (and its parameter ``key`` or port
        ``port``): its name, and its path in the file it was read from (a parameter's own
        when the component is the file's entry, else the entry of the subsystem it is in)."""
        entry = self.paths.get(component.name)
        own = entry is not None and "." not in component.name
        return {"component": component.name, "parameter": key, "port": port,
                "path": f"{entry}.params.{key}" if own and key else entry}

    def flat(self) -> Model:
        """The model with every subsystem expanded in place, names by path: what validation
        and compilation work on (the model itself when it places no subsystem). Kept while the
        structure does not change; parameter values are always the current ones."""
        if not has_subsystems(self):
            return self
        key = self.content_key()
        if self._flat is None or self._flat[0] != key:
            self._flat = (key, flatten(self))
        flat = self._flat[1]
        flat.parameters.update(self.parameters)
        flat.parameter_text = dict(self.parameter_text)     # the check of validate()'s key
        flat.initial = self.initial          # current, as the parameter values
        return flat

    def parameter_values(self, overrides: Mapping[str, float | str] | None = None
                         ) -> dict[str, float]:
        """Model parameters with ``overrides`` applied and checked; an override may be a
        number with a unit (``{"c": "2 N*m/rad"}``), in SI base units, checked against the
        units of the component parameters that use it."""
        # checked again: ``parameters`` is a plain dict that code may have written to directly
        values = {key: quantities.to_si(value, f"parameters.{key}")
                  for key, value in self.parameters.items()}
        for key, value in (overrides or {}).items():
            if key not in values and "." in key:
                instance, _, name = key.rpartition(".")
                raise ModelError(
                    f"params: {key!r} is a value of subsystem {instance!r}, a constant of "
                    f"its equations: change it with model.set_parameter({key!r}, value), or "
                    f"feed it from a model parameter (params={{{name!r}: \"my_{name}\"}} on "
                    f"the subsystem) to vary it without a new compilation")
            if key not in values:
                raise ModelError(f"params: unknown model parameter {key!r}"
                                 f"{suggest(key, values)}; parameters are "
                                 f"{', '.join(values) or 'none'}")
            values[key] = quantities.to_si(value, f"params.{key}")
            if isinstance(value, str):
                problems = quantities.check_use(value, quantities.uses(self, key),
                                                f"params.{key}", parameter=key)
                if problems:
                    raise ModelError(problems)
        return values

    def numeric_values(self, overrides: Mapping[str, float] | None = None
                       ) -> dict[str, dict[str, Any]]:
        """Every component parameter evaluated to numbers: {component name: {param: value}}.

        Gathers every unknown name, failed evaluation and violated bound into one ModelError.
        Time-dependent parameters are evaluated at t = 0. Subsystems' components are named
        by path.
        """
        if has_subsystems(self):
            return self.flat().numeric_values(overrides)
        env = self.parameter_values(overrides)
        env_t = {**env, "t": 0.0}
        out = {}
        # quantities given to model parameters (here, in definitions, to subsystems) against
        # the units of their uses: a flat model checks the model it expands
        problems = quantities.problems(self._source or self)
        for comp in self.components.values():
            vals = {}
            for key, spec in comp.params.items():
                where = self.place(comp, key)
                try:
                    vals[key] = evaluate(comp._values[key], spec, env_t, where,
                                         signal_outputs(self) if spec.signals else None)
                except ModelError as exc:
                    problems.extend(p.where(**self.fields(comp, key)) for p in exc.problems)
            out[comp.name] = vals
        if problems:
            raise ModelError(problems)
        return out

    def content_key(self, _memo=None):
        """What the equations of the model depend on, as a hashable value: the parameter
        names, every component (the object, its type and given parameters) and the wiring.
        Parameter *values* are not in it: they stay symbols in a compiled System. A placed
        definition is in it as a digest of its own key (``fingerprint``), each computed once:
        definitions that each place two of the next cost their number, not 2^depth."""
        memo = {} if _memo is None else _memo
        comps = tuple((id(c), name, c.signature(memo)) if isinstance(c, Subsystem) else
                      (id(c), name, type(c).__qualname__, repr(sorted(c.given.items())))
                      for name, c in self.components.items())
        wiring = tuple((a.path, id(a.component), b.path, id(b.component))
                       for a, b in self.connections)
        exposed = tuple((k, v.path, id(v.component)) for k, v in self.exposed.items())
        return tuple(self.parameters), comps, wiring, exposed

    def fingerprint(self, _memo=None):
        """A digest of ``content_key`` (a text of 64 hex digits), computed once per model in
        one walk (``_memo``)."""
        memo = {} if _memo is None else _memo
        if id(self) not in memo:
            import hashlib
            memo[id(self)] = hashlib.sha256(repr(self.content_key(memo)).encode()).hexdigest()
        return memo[id(self)]

    def validate(self) -> Topology:
        """Check the whole model; return its Topology or raise one ModelError listing all.

        The Topology of an unchanged model (same content, same parameter values) is kept, so
        loading a file and compiling it validate once."""
        from .topology import analyze
        if has_subsystems(self):
            flat = self.flat()
            try:
                return flat.validate()
            except ModelError as exc:             # in the user's names, not the flat ones
                raise user_names(exc, flat) from None
        key, values = self.content_key(), (dict(self.parameters), dict(self.parameter_text))
        if self._validated is not None and self._validated[:2] == (key, values):
            return self._validated[2]
        topology = analyze(self)
        self._validated = (key, values, topology)
        return topology

    def compile(self, loops: str = "projected", baumgarte_rate: float | None = None
                ) -> System:
        """Validate and build the equations: a ``kn.System``.

        ``loops`` chooses the formulation of kinematic loops (see ``kinetwork.equations.loops``):
        "projected" (default: an ODE for any method, its dependent coordinates carried only
        to start a Newton projection onto the closure in every evaluation; CVODES Adams runs
        it), "partition" (independent coordinates as the only differential states, the
        dependent ones algebraic variables solved exactly at every step: a DAE for IDAS,
        fewer states but slower and, below rtol 1e-8, less accurate) or "baumgarte" (an ODE in all
        coordinates, stabilised at ``baumgarte_rate`` [1/s], default 10; 0 leaves the drift
        unchecked). A model whose content has not changed since its last compilation gives
        the same System back, without building it again. A model of subsystems is compiled
        flat: states, signals and parameters are named by path (``"cyl1.slide.q"``).
        """
        if has_subsystems(self):
            flat = self.flat()
            try:
                return flat.compile(loops, baumgarte_rate)
            except ModelError as exc:             # in the user's names, not the flat ones
                raise user_names(exc, flat) from None
        key = (self.content_key(), loops, baumgarte_rate)
        with _compile_lock:
            if key not in self._compiled:
                # kinetwork.equations.stored.compile: loaded when kept on disk, else built
                system = upcall("compile")(self, loops=loops, baumgarte_rate=baumgarte_rate)
                # a System is built for one content: any other is stale now
                self._compiled = {k: v for k, v in self._compiled.items() if k[0] == key[0]}
                self._compiled[key] = system
            return self._compiled[key]

    def save(self, path: str | os.PathLike, overwrite: bool = False) -> None:
        """Write the model as JSON (atomically: a failed save leaves the old file whole).
        A file that is not a model file (a CSV, an image), a definition file this model
        places, a folder or a special file is refused (``overwrite=True`` replaces the
        first kind); see ``kinetwork.outputs``."""
        save(self, path, overwrite=overwrite)

    def files(self) -> list[str]:
        """The files this model was read from: its own (``kn.load``) and those of the
        subsystem definitions it places or keeps. What reads them never writes them."""
        if self._source is not None:                # a flat model: its model's files
            return self._source.files()
        found = [self.path] if self.path else []
        try:
            placed = definitions(self)
        except ModelError:                          # a cycle: refused where it matters
            placed = []
        for d in [*self.definitions.values(), *placed]:
            if d.origin is not None:
                found.append(d.origin[0])
        return list(dict.fromkeys(found))

    def _repr_svg_(self):
        """Jupyter shows a model as its wiring diagram (``kinetwork.diagram.svg``)."""
        return upcall("diagram")(self)

    def __repr__(self):
        return (f"<Model {self.name!r}: {len(self.components)} components, "
                f"{len(self.connections)} connections>")


def keep_topology(model, topology):
    """Keep ``topology`` as the validation of ``model``'s content: what a System kept on disk
    for that content was built from (``kinetwork.equations.stored``)."""
    model._validated = (model.content_key(), (dict(model.parameters),
                                              dict(model.parameter_text)), topology)


def evaluate(value, spec, env, where, signals=None):
    """A normalized parameter value evaluated with numbers; bounds checked. ``signals`` are
    the signal outputs (``"pos.y"``) it may read (None: not checked here, the model was
    validated): a value that reads one has no number before the simulation, so it evaluates
    to nan."""
    if value is None or spec.kind != "real":
        return value
    if spec.shape == ():
        return _scalar(value, spec, env, where, signals=signals)
    arr = np.array([[_scalar(v, spec, env, f"{where}[{i}][{j}]", bounds=False)
                     for j, v in enumerate(row)] for i, row in enumerate(value)]
                   if len(spec.shape) == 2 else
                   [_scalar(v, spec, env, f"{where}[{i}]", bounds=False, signals=signals)
                    for i, v in enumerate(value)])
    if spec.nonzero and not np.any(arr):
        raise ModelError(f"{where}: must not be the zero vector")
    return arr


def signal_outputs(model):
    """The signal outputs of a (flat) model's components by dotted name: what a parameter
    with ``signals`` may read ("pos.y")."""
    return sorted(f"{c.name}.{pname}" for c in model.components.values()
                  for pname, port in c.ports.items() if port.domain == "signal_out")


def _scalar(value, spec, env, where, bounds=True, signals=None):
    if isinstance(value, str):
        expr = parse(value)
        read = sorted(n for n in expr.names if "." in n)
        if read:
            wrong = [n for n in read if signals is not None and n not in signals]
            if wrong:
                close = suggest(wrong[0], signals)
                raise ModelError(f"{where} = {value!r}: {wrong[0]!r} is not a signal output "
                                 f"of this model{close}; signal outputs are "
                                 f"{', '.join(signals) or 'none'}", hint=hint(close))
        unknown = sorted(expr.names - set(env) - set(read))
        if unknown:
            close = suggest(unknown[0], env)
            raise ModelError(f"{where} = {value!r}: unknown name {unknown[0]!r}{close}; model "
                             f"parameters are {', '.join(k for k in env if k != 't') or 'none'}",
                             hint=hint(close))
        if read:
            return math.nan
        try:
            number = float(expr.evaluate(env))
        except (ZeroDivisionError, ValueError, OverflowError, TypeError) as exc:
            raise ModelError(f"{where} = {value!r}: cannot be evaluated ({exc})") from None
    else:
        number = float(value)
    if bounds:
        spec.check_bounds(number, where)
    elif not math.isfinite(number):
        raise ModelError(f"{where}: must be finite, got {number}")
    return number


def text_problem(text, allowed=""):
    """The problem with free text from a file, or None: lone surrogates (no file can hold
    them) and control characters other than ``allowed`` are refused, naming where."""
    for found in _NOT_TEXT.finditer(text):
        char = found.group()
        if char not in allowed:
            what = "a lone surrogate" if "\ud800" <= char <= "\udfff" else \
                f"the control character {char!r}"
            return f"{what} at character {found.start()} of {quote(text, 60)}"
    return None


def model_name_problem(name):
    """The problem with a model name, or None: any printable text up to MODEL_NAME_LIMIT
    characters (spaces and non-ASCII letters welcome), no control characters."""
    if not isinstance(name, str) or not name:
        return f"must be a non-empty string, got {quote(name, 40)}"
    if len(name) > MODEL_NAME_LIMIT:
        return f"at most {MODEL_NAME_LIMIT} characters, got {len(name)}: {quote(name, 60)}"
    return text_problem(name)
