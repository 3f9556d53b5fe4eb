"""The warm-up of the studio's forkserver: imported there only (``jobs.PRELOAD``), it builds,
compiles, runs and encodes a small model once, so that every child forked from it starts
with CasADi's plugins loaded and kinetwork's first-use caches filled (a first run in a cold
process costs several times the next). A failure here only leaves the children cold."""

import logging

log = logging.getLogger("kinetwork.studio")

#: a pendulum: a joint, a body, a spring on the joint, a probe
MODEL = {
    "format": "kinetwork.model", "version": 1, "name": "warm_up",
    "parameters": {"c": 1.0},
    "components": [
        {"name": "ground", "type": "multibody.Ground", "params": {}},
        {"name": "joint", "type": "multibody.Revolute", "params": {"q0": 0.1}},
        {"name": "body", "type": "multibody.RigidBody",
         "params": {"mass": 1.0, "r_cm": [0, -0.5, 0]}},
        {"name": "spring", "type": "rotational.SpringDamper", "params": {"c": "c", "d": 0.1}},
        {"name": "probe", "type": "Probe", "params": {"quantities": ["angle", "torque"]}},
    ],
    "connections": [["ground.frame", "joint.frame_a"], ["joint.frame_b", "body.frame_a"],
                    ["spring.flange_a", "joint.support"], ["spring.flange_b", "joint.axis"],
                    ["probe.port", "joint.axis"]],
    "simulation": {"t_end": 0.1, "n_points": 11},
}


def warm():
    """One model through every step a child takes: check, compile, run, encode."""
    from ..solver.plan import simulate
    from .checks import build, context, validate
    from .results import encode, results_json
    ctx = context(None, [])
    validate(MODEL, ctx)
    model = build(MODEL, ctx, validate=True)
    encode(results_json(simulate(model.compile()), model))


try:
    warm()
except Exception:        # noqa: BLE001 -- cold children still work
    log.debug("the studio's warm-up failed", exc_info=True)
