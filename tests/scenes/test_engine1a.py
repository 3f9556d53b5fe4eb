"""MSL's Engine1a (``models/engine1a.json``), started where MSL starts it: at its top dead
centre, where the loop's Jacobian is singular, from MSL's own start values (B1 = B2 = 0 and
the slider at 0.15, none fixed). The slider-crank's closed form is the reference:
s(phi) = 0.35 - 0.1 cos(phi) - sqrt(0.2^2 - 0.1^2 sin^2(phi)) along the cylinder."""

import pathlib

import numpy as np

import kinetwork as kn
from scenes import engine

MODEL = pathlib.Path(__file__).resolve().parents[2] / "models" / "engine1a.json"


def closed_form(phi):
    return 0.35 - 0.1 * np.cos(phi) - np.sqrt(0.2**2 - (0.1 * np.sin(phi))**2)


def test_engine1a_assembles_at_its_top_dead_centre_from_msl_start_values():
    system = kn.load(MODEL).compile(loops="partition")
    assert system.state_names == ["Bearing.q", "Bearing.qd"]
    x, z = system.initial_full_p(system.param_vector())
    assert np.allclose(x, [0.0, 10.0])
    s = z[system.algebraic_names.index("Cylinder.q")]
    assert abs(s - closed_form(0.0)) < 1e-12          # 0.05, not MSL's guess of 0.15


def test_engine1a_runs_through_its_dead_centres_on_the_closed_form():
    res = kn.simulate(kn.load(MODEL), t_end=2.0, n_points=201, rtol=1e-10, atol=1e-12)
    phi = res["crank.angle"]
    assert phi[-1] > 6 * np.pi                        # past several dead centres
    assert np.max(np.abs(res["piston.position"] - closed_form(phi))) < 1e-9


def test_the_example_file_is_what_the_builder_writes(tmp_path):
    engine.build_engine1a().save(tmp_path / "engine1a.json")
    assert (tmp_path / "engine1a.json").read_bytes() == MODEL.read_bytes()
