"""MSL Rotational.Examples.CoupledClutches wired as MSL wires it, against the same drive
train written out by hand and integrated by scipy with its own event location
(``scenes/clutches.py``): clutch2 is free until T2 = 0.4 s (its normal force is 0), clutch3
until T3 = 0.9 s, and clutch1 from 1.25 s, where its normal force 20 cos(2 pi 0.2 t) falls
to zero (MSL: fn <= 0 is free)."""

import numpy as np

import kinetwork as kn
from scenes import clutches


def test_coupled_clutches_on_the_hand_written_reference():
    t = np.linspace(0.0, 1.5, 151)
    res = kn.simulate(clutches.model(), t_end=1.5, n_points=151, rtol=1e-10, atol=1e-10)
    phi, w = clutches.reference(t)
    for k in range(4):
        np.testing.assert_allclose(res[f"J{k + 1}.w"], w[:, k], atol=1e-6 * 10)
        np.testing.assert_allclose(res[f"J{k + 1}.phi"], phi[:, k], atol=1e-6 * 10)
    # the clutches' modes: each free while unpressed, and clutch1 free again at the end
    modes = {k: res[f"clutch{k}.mode"] for k in (1, 2, 3)}
    assert np.all(modes[2][t < 0.39] == 2) and np.all(modes[3][t < 0.89] == 2)
    assert np.all(modes[2][t > 0.41] != 2) and np.all(modes[1][t > 1.26] == 2)
    assert np.ptp(w[:, 3]) > 1.0                  # J4 is dragged along once clutch3 holds


def test_a_clutch_with_no_normal_force_transmits_nothing():
    """The issue's pair: two unit inertias through Clutch(mu=0.5, fn_max=20,
    f_normalized=0), 1 N*m on the first from t = 0.5: the first turns at 0.5 rad/s at t = 1,
    the second stays."""
    rot = kn.rotational
    m = kn.Model("pair")
    m.add(rot.Inertia("a", J=1.0))
    m.add(rot.Inertia("b", J=1.0))
    m.add(rot.Clutch("clutch", mu=0.5, fn_max=20.0, f_normalized=0.0))
    m.add(rot.Torque("push", tau="if_else(t >= 0.5, 1, 0)"))
    for x, y in [("push.flange", "a.flange_a"), ("a.flange_b", "clutch.flange_a"),
                 ("clutch.flange_b", "b.flange_a")]:
        m.connect(x, y)
    res = kn.simulate(m, t_end=1.0, n_points=3, rtol=1e-10, atol=1e-12)
    assert abs(res["a.w"][-1] - 0.5) < 1e-9
    assert abs(res["b.w"][-1]) < 1e-12 and res["clutch.mode"][-1] == 2
    brake = kn.Model("brake")
    brake.add(rot.Inertia("a", J=1.0, w0=2.0))
    brake.add(rot.Brake("brake", mu=0.5, fn_max=20.0, f_normalized=-0.5))
    brake.connect("a.flange_b", "brake.flange")
    res = kn.simulate(brake, t_end=1.0, n_points=3, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["a.w"], 2.0, atol=1e-12)     # a brake that does not press
