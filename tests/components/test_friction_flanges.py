"""MSL's port layout of Brake and BearingFriction: flange_a and flange_b rigidly joined (one
node with ``flange``), an optional support; a drive train wired through them one to one."""

import numpy as np
import pytest

import kinetwork as kn

J1, J2, W0 = 0.3, 0.2, 10.0
MU, CGEO, FN = 0.4, 0.1, 50.0               # brake torque mu cgeo fn = 2 N*m


def drive(form, kind="brake", support=False):
    """Rotor a -> friction -> rotor b, the friction wired as MSL ('two': a to flange_a,
    flange_b to b) or to its one node ('one'); its support unwired or on a Fixed."""
    model = kn.Model("drive")
    a = model.add(kn.rotational.Inertia("a", J=J1, w0=W0))
    b = model.add(kn.rotational.Inertia("b", J=J2))
    if kind == "brake":
        f = model.add(kn.rotational.Brake("f", mu=MU, cgeo=CGEO, fn_max=FN, peak=1.2))
    else:
        f = model.add(kn.rotational.BearingFriction("f", tau_c=MU * CGEO * FN, peak=1.2))
    probe = model.add(kn.Probe("p", quantities=["torque"]))
    if form == "two":
        model.connect(a.flange_b, f.flange_a)
        model.connect(f.flange_b, b.flange_a)
    else:
        model.connect(a.flange_b, f.flange)
        model.connect(f.flange, b.flange_a)
    model.connect(probe.port, f.flange)
    if support:
        housing = model.add(kn.rotational.Fixed("housing"))
        model.connect(f.support, housing.flange)
    return model


@pytest.mark.parametrize("form, kind, support", [("two", "brake", False),
                                                 ("two", "bearing", True),
                                                 ("one", "brake", True)])
def test_two_rotors_through_the_friction_stop_at_the_closed_form_time(form, kind, support,
                                                                      tmp_path):
    # (J1 + J2) w' = -mu cgeo fn: both stop at (J1 + J2) W0 / (mu cgeo fn) = 2.5 s
    path = tmp_path / "drive.json"
    drive(form, kind, support).save(path)              # the file form wires the same
    res = kn.simulate(kn.load(path), t_end=3.0, n_points=31, method="cvodes", rtol=1e-11,
                      atol=1e-13, jit=False)
    t_stop = (J1 + J2) * W0 / (MU * CGEO * FN)
    events = res.stats["events"]
    assert [(e["component"], e["kind"]) for e in events] == [("f", "stuck")]
    assert abs(events[0]["t"] - t_stop) < 1e-9
    moving = res.t < t_stop
    np.testing.assert_allclose(res["a.w"][moving], W0 - res.t[moving] / t_stop * W0,
                               atol=1e-9)
    assert np.all(res["a.w"][~moving] == 0.0)
    # the probe on the node reads the friction torque: mu cgeo fn sliding, none stuck
    np.testing.assert_allclose(res["p.torque"][moving], MU * CGEO * FN, rtol=1e-12)
    np.testing.assert_allclose(res["p.torque"][~moving], 0.0, atol=1e-12)


def test_a_friction_wired_to_nothing_is_refused_by_name():
    model = kn.Model("loose")
    model.add(kn.rotational.Brake("brake", mu=MU, fn_max=FN))
    with pytest.raises(kn.ModelError, match=r"brake\.flange.*brake\.flange_a.*brake\.flange_b"):
        model.compile()
