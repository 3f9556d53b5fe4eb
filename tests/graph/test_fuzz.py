"""Mutated model files: every outcome is a working model or a ModelError, nothing else."""

import copy
import json
import pathlib

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import kinetwork as kn

MODELS = sorted((pathlib.Path(__file__).resolve().parents[2] / "models").glob("*.json"))
BASES = [json.loads(p.read_text()) for p in MODELS]

scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-10**30, 10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["", "L1", "-L1/2", "1/0", "sqrt(-1)", "__import__('os')", "t", "m1*",
                     "ground.frame", "mass1.frame_a", "shoulder.axis", "probe1.port",
                     "multibody.Revolute", "rotational.Spring", "Probe", "nope.nope",
                     "angle", "10**400", "exp(1000)"]),
    st.text(max_size=12))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=3)),
    max_leaves=8)


def paths(node, prefix=()):
    """Every place in a JSON document, as a tuple of keys and indices."""
    yield prefix
    items = node.items() if isinstance(node, dict) else enumerate(node) \
        if isinstance(node, list) else ()
    for key, child in items:
        yield from paths(child, prefix + (key,))


@st.composite
def mutated(draw):
    doc = copy.deepcopy(draw(st.sampled_from(BASES)))
    for _ in range(draw(st.integers(1, 3))):
        places = [p for p in paths(doc) if p]
        where = draw(st.sampled_from(places))
        parent = doc
        for key in where[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["set", "delete", "add", "duplicate"]))
        if action == "set":
            parent[where[-1]] = draw(values)
        elif action == "delete":
            del parent[where[-1]]
        elif action == "add" and isinstance(parent, dict):
            parent[draw(st.text(max_size=8))] = draw(values)
        elif action == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[where[-1]]))
    return doc


@settings(max_examples=400, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_files_load_or_are_refused(doc):
    text = json.dumps(doc)
    try:
        model = kn.loads(text)
    except kn.ModelError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
        return
    try:
        system = model.compile()     # a loop that cannot close is refused only here
    except kn.ModelError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
        assert "kinematic loop through" in str(exc)
        return
    x0 = system.x0
    assert np.all(np.isfinite(x0))
    again = kn.loads(kn.dumps(model))
    assert kn.dumps(again) == kn.dumps(model)
