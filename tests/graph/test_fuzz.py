"""Mutated model files: every outcome is a working model or a ModelError, nothing else."""

import copy
import json
import pathlib

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import kinetwork as kn

MODELS = sorted((pathlib.Path(__file__).resolve().parents[2] / "models").glob("*.json"))
#: and the models of subsystems, their definitions inline (a text has no folder to find files)
BASES = [json.loads(p.read_text()) for p in MODELS] + [
    json.loads(kn.dumps(kn.load(p))) for p in
    sorted((MODELS[0].parent / "robot").glob("arm_*.json"))]

scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-10**30, 10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["", "L1", "-L1/2", "1/0", "sqrt(-1)", "__import__('os')", "t", "m1*",
                     "ground.frame", "mass1.frame_a", "shoulder.axis", "probe1.port",
                     "multibody.Revolute", "rotational.Spring", "Probe", "nope.nope",
                     "angle", "10**400", "exp(1000)", "signals.PID", "rotational.IdealGear",
                     "multibody.Spherical", "pid_shoulder.y", "motor_elbow.u", "C.frame_b",
                     "rotor.flange_a", "value", "idas", "rk45"]),
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
        action = draw(st.sampled_from(["set", "delete", "add", "duplicate", "perturb",
                                       "perturb", "rewire"]))
        target = parent[where[-1]]
        if action == "perturb" and isinstance(target, (int, float)) \
                and not isinstance(target, bool):
            # a plausible number instead: the model stays loadable more often, so the
            # deeper stages (compile, simulate) are reached
            parent[where[-1]] = draw(st.sampled_from([0.0, -1.0, 1e-9, 1e9])) if draw(
                st.booleans()) else target * draw(st.floats(-3, 3, allow_nan=False))
        elif action == "rewire" and isinstance(target, str) and "." in target:
            ports = sorted({p for pair in doc.get("connections", []) if isinstance(pair, list)
                            for p in pair if isinstance(p, str)})
            if ports:
                parent[where[-1]] = draw(st.sampled_from(ports))
        elif action == "set":
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
# an inertia no rigid body has is simulated with a warning (an idealisation, as MSL's
# examples use): a working model, not a failure of the loader
@pytest.mark.filterwarnings("ignore::kinetwork.IdealisedInertiaWarning")
@given(mutated())
def test_mutated_files_load_or_are_refused(doc):
    text = json.dumps(doc)
    try:
        model = kn.loads(text)
    except kn.ModelError as exc:
        event("refused when loaded")
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
        return
    try:
        system = model.compile()     # loops that cannot close, singular bodies: refused here
    except kn.ModelError as exc:
        event("refused when compiled")
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
        return
    event("compiled")
    x0 = system.x0
    assert np.all(np.isfinite(x0))
    again = kn.loads(kn.dumps(model))
    assert kn.dumps(again) == kn.dumps(model)


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
# an inertia no rigid body has is simulated with a warning (an idealisation, as MSL's
# examples use): a working model, not a failure of the loader
@pytest.mark.filterwarnings("ignore::kinetwork.IdealisedInertiaWarning")
@given(mutated())
def test_mutated_models_simulate_or_fail_cleanly(doc):
    """Further: a short run of what compiles ends in Results, a ModelError (bad settings) or
    a SimulationError holding what it computed; never anything else, never a hang."""
    try:
        system = kn.loads(json.dumps(doc)).compile()
    except kn.ModelError:
        event("refused")
        return
    try:
        res = kn.simulate(system, t_end=0.05, n_points=3, time_limit=5.0)
    except kn.ModelError as exc:
        event("settings refused")
        assert exc.problems
        return
    except kn.SimulationError as exc:
        event("simulation failed, partial results kept")
        assert exc.results is not None and exc.reason
        assert len(exc.results.t) >= 1 and np.all(np.isfinite(exc.results.states))
        return
    event("simulated")
    assert res.t[-1] == 0.05 and np.all(np.isfinite(res.states))
