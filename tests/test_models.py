"""Every saved example model loads, saves back byte for byte, simulates and plots (a
subsystem definition, a model with exposed ports, is simulated where it is placed)."""

import pathlib
import shutil

import matplotlib
import numpy as np
import pytest

import kinetwork as kn

matplotlib.use("Agg")
MODELS = sorted((pathlib.Path(__file__).resolve().parents[1] / "models").glob("**/*.json"))
SCENES = [p for p in MODELS if "ports" not in p.read_text()[:2000]]
#: more components than this (flat) run a short time without the C compiler in this test
LARGE = 100


def test_seed_model_is_there():
    assert "double_pendulum.json" in [p.name for p in MODELS]


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_round_trip_byte_for_byte(path, tmp_path):
    folder = tmp_path / "models"             # with the files it references, in their places
    shutil.copytree(path.parent, folder)
    model = kn.load(folder / path.name)
    out = folder / f"again_{path.name}"
    model.save(out)
    assert out.read_bytes() == path.read_bytes()


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_simulates_and_plots(path):
    model = kn.load(path)
    large = len(model.flat().components) > LARGE
    res = kn.simulate(model, n_points=201, **({"t_end": 0.05, "jit": False} if large else {}))
    assert np.all(np.isfinite(res.states))
    assert res.signal_names, f"{path.name} has no probes"
    fig = res.plot()
    assert len(fig.axes) >= len(res.signal_names)
    matplotlib.pyplot.close(fig)


def test_seed_model_is_the_paper():
    model = kn.load(MODELS[[p.name for p in MODELS].index("double_pendulum.json")])
    system = model.compile()
    assert system.state_names == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
    np.testing.assert_allclose(system.x0, [0.05, 0.05, 0, 0])
    assert model.parameters == {"L1": 1.0, "L2": 1.0, "m1": 1.0, "m2": 1.0, "c": 1.0,
                                "d": 1.0, "g": 9.8}
    assert model.simulation["t_end"] == 10.0
    assert set(kn.simulate(system, n_points=11).probes) == {"probe1", "probe2"}
