"""Component parameters by path in every analysis: a sweep, a sample, a sensitivity, a fit,
a linearisation and a trim of ``"spring.c"`` on models written without any model
parameter, against closed forms (and central differences of tight runs)."""

import numpy as np
import pytest
from close import assert_same_numbers
from scenes.oscillator import closed_form, oscillator, stage

import kinetwork as kn
from kinetwork.graph import model as graph_model

FAST = {"t_end": 2.0, "n_points": 101, "jit": False, "progress": False}


def test_a_sweep_of_component_paths_on_a_model_without_parameters(monkeypatch):
    model = oscillator()
    assert model.parameters == {}
    built = []
    real = graph_model.upcall

    def counting_upcall(name):
        build = real(name)
        return (lambda *a, **k: built.append(1) or build(*a, **k)) if name == "compile" \
            else build
    monkeypatch.setattr(graph_model, "upcall", counting_upcall)
    ds = kn.sweep(model, {"spring.c": [1.0, 4.0, 9.0], "mass.m": ["1 kg", "2000 g"]},
                  rtol=1e-9, atol=1e-11, **FAST)
    assert built == [1]                            # one compilation for six members
    assert dict(ds.sizes) == {"spring.c": 3, "mass.m": 2, "t": 101}
    assert ds["spring.c"].attrs["units"] == "N/m" and ds["mass.m"].attrs["units"] == "kg"
    assert_same_numbers(ds["mass.m"].values, [1.0, 2.0])
    assert "spring.c -> spring_c" in ds.attrs["lifted"]
    for c in (1.0, 4.0, 9.0):
        for m in (1.0, 2.0):
            np.testing.assert_allclose(ds["probe.position"].sel({"spring.c": c, "mass.m": m}),
                                       closed_form(ds.t.values, c, m), atol=1e-8)
    with pytest.raises(kn.ModelError, match=r"sweep: mass.m\[0\]: .*does not convert"):
        kn.sweep(model, {"mass.m": ["1 m"]}, **FAST)
    refused = kn.sweep(model, {"mass.m": [1.0, -1.0]}, **FAST)
    assert refused.status.values.tolist() == ["ok", "failed"]
    assert "mass.m = -1.0 kg: must be >= 0" in refused.reason.values[1]


def test_a_sample_of_a_path_inside_a_subsystem():
    model = stage()
    ds = kn.sample(model, {"cyl3.mass.m": kn.uniform(0.5, 2.0)}, n=4, seed=1, rtol=1e-9,
                   atol=1e-11, **FAST)
    for k in range(4):
        m = float(ds["cyl3.mass.m"].values[k])
        np.testing.assert_allclose(ds["cyl3.probe.position"].values[k],
                                   closed_form(ds.t.values, 9.0, m), atol=1e-8)


def test_sensitivity_to_a_path_against_the_closed_form_and_central_differences():
    """x = x0 cos(w t), w = sqrt(c/m): dx/dc = -x0 t sin(w t) / (2 m w); and against central
    differences of tight runs, within rtol of the default (1e-8) times the scale."""
    model = oscillator()
    sens = kn.sensitivity(model, ["spring.c", "mass.m"], t_end=2.0, n_points=21,
                          outputs=["probe.position"])
    t, c, m = sens.t, 4.0, 1.0
    w = np.sqrt(c / m)
    exact = -0.1 * t * np.sin(w * t) / (2 * m * w)
    np.testing.assert_allclose(sens["probe.position", "spring.c"], exact, atol=1e-8 * 0.2)
    np.testing.assert_allclose(sens["probe.position", "mass.m"], -exact * c / m,
                               atol=1e-8 * 0.2)
    h = 1e-4
    tight = {"t_end": 2.0, "n_points": 21, "rtol": 1e-12, "atol": 1e-14, "jit": False}
    fd = (kn.simulate(model, params={"spring.c": c + h}, **tight)["probe.position"] -
          kn.simulate(model, params={"spring.c": c - h}, **tight)["probe.position"]) / (2 * h)
    np.testing.assert_allclose(sens["probe.position", "spring.c"], fd, atol=1e-7 * 0.2)


def test_a_fit_of_a_path_converges():
    model = oscillator()
    t = np.linspace(0, 2.0, 41)
    data = {"t": t, "probe.position": closed_form(t, 6.25, 1.0)}
    result = kn.fit(model, data, {"spring.c": (0.5, 20.0)})
    assert result.success
    assert result.params["spring.c"] == pytest.approx(6.25, rel=1e-6)


def test_linearize_and_trim_by_path():
    model = oscillator()
    lin = kn.linearize(model, outputs=["probe.position"], params={"spring.c": "9 N/m"})
    assert sorted(np.abs(lin.eigenvalues.imag)) == pytest.approx([3.0, 3.0])
    # trim: the spring stiffness that holds the mass at rest 0.2 m out under a 2 N force
    pushed = oscillator()
    pushed.add(kn.translational.Force("push", f=2.0))
    pushed.connect("push.flange", "mass.flange_a")
    eq = kn.equilibrium(pushed, free=["spring.c"], fix={"mass.s": 0.2})
    assert eq.params == {"spring.c": pytest.approx(10.0)}


def test_a_member_with_events_is_simulates_run():
    """MSL's friction example (clutch and brake events, no model parameter): each member of
    a sweep of its spring is the run simulate makes, events and all."""
    model = kn.load("models/msl_friction.json")
    settings = {"t_end": 0.6, "n_points": 61, "jit": False}
    ds = kn.sweep(model, {"spring.c": [1e4, 2e4]}, progress=False, **settings)
    for c in (1e4, 2e4):
        res = kn.simulate(model, params={"spring.c": c}, **settings)
        assert res.stats["events"]
        for name in res.state_names:
            assert_same_numbers(ds[name].sel({"spring.c": c}).values, res[name])
