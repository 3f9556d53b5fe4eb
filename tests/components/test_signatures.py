"""Self-documenting components (issue 19, item 1): every component type's signature,
docstring and reference data are generated from its Param and Port declarations, and say the
same as the declarations (and as the compiled equations, for the units of joint coordinates).
"""

import functools
import importlib
import inspect
import json
import pathlib
import pydoc
import typing

import matplotlib.figure
import pytest

import kinetwork as kn
from kinetwork import units
from kinetwork.components.base import REGISTRY
from kinetwork.components.quantities import QUANTITIES
from kinetwork.components.reference import param_line, reference

TYPES = sorted(REGISTRY)


def test_help_shows_the_real_signature_with_units_defaults_and_ports():
    text = pydoc.render_doc(kn.multibody.RigidBody, renderer=pydoc.plaintext)
    assert ("RigidBody(name: str, *, mass: float | str, r_cm: list[float | str] = "
            "(0.0, 0.0, 0.0), inertia: list[list[float | str]] = ") in text
    assert "mass : kg, >= 0, required" in text
    assert "r_cm : m, 3 values, default [0, 0, 0]" in text
    assert "inertia : kg*m^2, 3x3 or its diagonal" in text
    assert "frame_a (frame)\n |      Frame the body is fixed to" in text
    assert "angular_velocity [rad/s]" in text, "what a probe at frame_a records"
    assert text.count("Parameters\n |  ----------") == 1, "the written list is replaced"
    ground = pydoc.render_doc(kn.multibody.Ground, renderer=pydoc.plaintext)
    assert "gravity : m/s^2, 3 values, default [0, -9.81, 0]" in ground


@pytest.mark.parametrize("type_name", TYPES)
def test_the_signature_is_the_declarations(type_name):
    cls = REGISTRY[type_name]
    sig = inspect.signature(cls)
    assert list(sig.parameters) == ["name", *cls.params]
    for key, spec in cls.params.items():
        p = sig.parameters[key]
        assert p.kind is inspect.Parameter.KEYWORD_ONLY
        if spec.required:
            assert p.default is inspect.Parameter.empty
        else:
            assert json.dumps(p.default) == json.dumps(spec.default), key
    # it is what the constructor takes: refused keywords are refused by both
    with pytest.raises(TypeError):
        sig.bind("x", no_such_parameter=1)


@pytest.mark.parametrize("type_name", TYPES)
def test_every_parameter_has_a_doc_and_a_unit_pint_reads(type_name):
    cls = REGISTRY[type_name]
    for key, spec in cls.params.items():
        assert spec.doc.strip(), f"{type_name}.{key} has no doc"
        if spec.kind != "real":
            continue
        # "" is the unit of a signal block's signal (any, converted to SI); nothing else may
        # leave its unit out ("1" is dimensionless)
        assert spec.unit or type_name.startswith("signals."), \
            f"{type_name}.{key}: no unit (a dimensionless one is unit=\"1\")"
        assert isinstance(spec.unit, str), "what forms and tables show"
        for unit in spec.entry_units or (spec.unit,):
            assert units.check_unit(unit), f"{type_name}.{key}: pint cannot read {unit!r}"


@pytest.mark.parametrize("type_name", TYPES)
def test_the_docstring_and_the_data_say_the_same(type_name):
    cls = REGISTRY[type_name]
    ref = reference(cls)
    json.dumps(ref)                                   # data, ready for the studio and docs
    doc = inspect.getdoc(cls)
    assert " ".join(doc.split()).startswith(ref["summary"])
    assert ref["summary"] == " ".join(cls._own_doc.partition("\n\n")[0].split()), \
        "the summary is the whole first paragraph"
    for info in ref["params"]:
        assert f"{info['name']} : {param_line(info)}\n    {info['doc']}" in doc
    for port in ref["ports"]:
        assert port["name"] in doc and port["doc"] in doc
        assert port["quantities"] == [
            {"name": n, "unit": q.unit, "shape": list(q.shape)}
            for n, q in QUANTITIES.get(port["domain"], {}).items()]
    schema = next(b for b in kn.schema()["properties"]["components"]["items"]["oneOf"]
                  if b.get("title") == type_name) if type_name == TYPES[0] else None
    if schema is not None:
        for info in ref["params"]:
            assert schema["properties"]["params"]["properties"][info["name"]][
                "description"] == f"{info['doc']} ({param_line(info)})"


def _joint_model(joint):
    model = kn.Model("m")
    model.add(kn.multibody.Ground("ground"))
    model.add(joint)
    model.add(kn.multibody.RigidBody("body", mass=1.0, inertia=[1.0, 1.0, 1.0]))
    model.connect("ground.frame", f"{joint.name}.frame_a")
    model.connect(f"{joint.name}.frame_b", "body.frame_a")
    return model


@pytest.mark.parametrize("cls", [kn.multibody.Revolute, kn.multibody.Prismatic,
                                 kn.multibody.Universal, kn.multibody.Cylindrical,
                                 kn.multibody.Planar], ids=lambda c: c.__name__)
def test_initial_values_carry_the_units_of_the_states_they_start(cls):
    # the units declared for q0 and qd0 are those the compiled System gives its states
    system = _joint_model(cls("j")).compile()
    units_of = dict(zip(system.state_names, system.state_units))
    q0 = cls.params["q0"].entry_units or (cls.params["q0"].unit,)
    qd0 = cls.params["qd0"].entry_units or (cls.params["qd0"].unit,)
    n = len(q0)
    coords = [name for name in system.state_names if "qd" not in name][:n]
    speeds = [name for name in system.state_names if "qd" in name][:n]
    assert [units_of[c] for c in coords] == list(q0)
    assert [units_of[s] for s in speeds] == list(qd0)


# -- type hints of the public API (issue 19, item 6) ------------------------------------------
def _public_callables():
    yield "kn.simulate", kn.simulate
    yield "kn.load", kn.load
    yield "kn.loads", kn.loads
    yield "kn.dumps", kn.dumps
    for cls in (kn.Model, kn.Results, kn.System):
        for name, member in vars(cls).items():
            if name.startswith("_") and name not in ("__init__", "__getitem__"):
                continue
            if isinstance(member, property):
                member = member.fget
            elif isinstance(member, functools.cached_property):
                member = member.func
            if callable(member):
                yield f"{cls.__name__}.{name}", member


PUBLIC = dict(_public_callables())
ANNOTATED = ["kn.simulate", "kn.load", "kn.loads", "kn.dumps", "Model.__init__",
             "Model.set_parameter", "Model.add", "Model.set_initial", "Model.expose",
             "Model.connect", "Model.port", "Model.flat", "Model.parameter_values",
             "Model.numeric_values", "Model.validate", "Model.compile", "Model.save",
             "Results.__init__", "Results.__getitem__", "Results.keys", "Results.method",
             "Results.probes", "Results.to_csv", "Results.to_pandas", "Results.to_xarray",
             "Results.summary", "Results.plot", "Results.animate", "System.rhs",
             "System.mass_matrix", "System.dynamics_terms", "System.x0", "System.outputs",
             "System.initial_state", "System.param_vector", "System.n_states", "System.dof"]


@pytest.mark.parametrize("name", ANNOTATED)
def test_the_public_api_is_annotated_and_its_annotations_resolve(name):
    func = PUBLIC[name]
    sig = inspect.signature(func)
    for p in sig.parameters.values():
        if p.name != "self":
            assert p.annotation is not inspect.Parameter.empty, f"{name}({p.name}) has no type"
    if not name.endswith("__init__"):
        assert sig.return_annotation is not inspect.Signature.empty, f"{name}: no return type"
    # the names used only for annotations (imported under TYPE_CHECKING, as the layers ask)
    # are the real ones: the hints resolve with kinetwork's public names and its optional
    # libraries
    names = {"Model": kn.Model, "System": kn.System, "Results": kn.Results,
             "Topology": kn.graph.topology.Topology, "Signal": kn.equations.signals.Signal,
             "pandas": importlib.import_module("pandas"),
             "xarray": importlib.import_module("xarray"),
             "Figure": matplotlib.figure.Figure}
    typing.get_type_hints(func, globalns={**func.__globals__, **names})


def test_the_package_says_it_is_typed():
    assert (pathlib.Path(kn.__file__).parent / "py.typed").is_file()
