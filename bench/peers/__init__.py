"""The tools a kinetwork user would otherwise reach for, behind one interface.

Each module builds its own model from a scene's plain data (``ChainSpec`` of
``tests/scenes/chains.py``):

``NAME``
    the tool as it appears in tables
``build(spec, **options) -> built``
    everything done once per model (model creation, derivation, compilation)
``run(built, t, **options) -> q``
    joint angles (len(t), N) at the times ``t``, from ``spec.q0``, ``spec.qd0`` at ``t[0]``
``trajectory(built, t, **options) -> (q, qd)``
    the same with the joint rates
``variants() -> list of dict``
    the option sets of a work-precision sweep, coarse to fine for each method
``TIGHTEST``
    the option set of the most accurate run
``energy(built, q, qd)``
    total mechanical energy with the springs (pinocchio and MuJoCo only)

Modules: ``pinocchio_peer`` (``pin.aba`` + scipy), ``mujoco_peer`` (MJCF + ``mj_step``),
``sympy_peer`` (Kane's method + lambdify + scipy DOP853). ``check.py`` checks them against
kinetwork; ``sympy_growth.py`` times sympy's derivation against N.
"""
