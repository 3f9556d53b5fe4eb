"""Results (kinetwork/solver/results.py), built by hand from Signal descriptors: shapes,
keys, CSV columns, the partial-run line and the atomic write."""

import csv
import json
import os

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.equations.signals import Signal
from kinetwork.solver.results import Results

SIGNALS = [Signal("p.angle", "rad", (), "p", "angle", "j.axis"),
           Signal("f.position", "m", (3,), "f", "position", "b.frame_a"),
           Signal("f.orientation", "", (3, 3), "f", "orientation", "b.frame_a")]
T = np.array([0.0, 0.5, 1.0])


def results():
    """Three points; each signal's values say where they sit: 100 * row + column."""
    n = sum(s.size for s in SIGNALS)
    values = 100 * np.arange(len(T))[:, None] + np.arange(n)[None, :]
    states = np.column_stack([T * 2, T * 3])
    return Results(T, states, ["j.q", "j.qd"], values, SIGNALS, state_units=["rad", "rad/s"],
                   probe_targets={"p": "j.axis", "f": "b.frame_a"})


def test_signals_read_in_their_shapes():
    res = results()
    assert res["p.angle"].shape == (3,)
    assert res["f.position"].shape == (3, 3)
    assert res["f.orientation"].shape == (3, 3, 3)
    np.testing.assert_array_equal(res["p.angle"], [0, 100, 200])
    np.testing.assert_array_equal(res["f.position"][1], [101, 102, 103])
    # the matrix is row-major in the values: R[i, j] is column 4 + 3 i + j
    np.testing.assert_array_equal(res["f.orientation"][2], 200 + 4 + np.arange(9).reshape(3, 3))


def test_keys_states_units_and_probes():
    res = results()
    assert res.keys() == ["t", "p.angle", "f.position", "f.orientation", "j.q", "j.qd"]
    assert all(key in res for key in res.keys()) and "p.speed" not in res
    np.testing.assert_array_equal(res["t"], T)
    np.testing.assert_array_equal(res["j.qd"], 3 * T)
    assert res.units == {"p.angle": "rad", "f.position": "m", "f.orientation": "",
                         "j.q": "rad", "j.qd": "rad/s"}
    assert res.probes == {"p": ["angle"], "f": ["position", "orientation"]}
    assert res.signals["f.position"] is SIGNALS[1] and res.signal_names == list(res.signals)
    assert len(res) == 3 and res.partial is None


def test_an_unknown_key_suggests_the_closest():
    with pytest.raises(KeyError, match=r"'p\.angel' \(did you mean 'p\.angle'\?\); available: "
                                       r"t, p\.angle"):
        results()["p.angel"]


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def test_csv_names_a_column_per_entry(tmp_path):
    res = results()
    res.to_csv(tmp_path / "out.csv")
    rows = read_csv(tmp_path / "out.csv")
    assert rows[0] == ["t", "p.angle", "f.position[0]", "f.position[1]", "f.position[2]",
                       *[f"f.orientation[{i},{j}]" for i in range(3) for j in range(3)]]
    assert len(rows) == 4
    data = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(data[:, 0], T)
    np.testing.assert_array_equal(data[2, 1:], 200 + np.arange(13))
    assert res.columns()[0] == rows[0]


def test_a_partial_run_says_so_in_its_sidecar_not_in_the_table(tmp_path):
    res = results()
    res.partial = {"t_reached": 1.0, "reason": "the step size\nfell below   the minimum"}
    res.to_csv(tmp_path / "out.csv")
    lines = (tmp_path / "out.csv").read_text().splitlines()
    assert len(lines) == 4 and not any(line.startswith("#") for line in lines)
    meta = json.loads((tmp_path / "out.meta.json").read_text())
    assert meta["partial"] == {"t_reached": 1.0,
                               "reason": "the step size fell below the minimum"}


def test_a_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "out.csv"
    path.write_text("t,old\n0.0,1.0\n")            # the last run's table

    def full_disk(*args):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", full_disk)
    with pytest.raises(OSError, match="No space left"):
        results().to_csv(path)
    assert path.read_text() == "t,old\n0.0,1.0\n"
    assert os.listdir(tmp_path) == ["out.csv"]           # no temporary file left behind


def test_a_simulation_gives_results_of_its_systems_signals(seed_model):
    res = kn.simulate(seed_model, t_end=0.5, n_points=6)
    assert list(res.signals.values()) == seed_model.compile().signals
    assert res.probe_targets == {"probe1": "shoulder.axis", "probe2": "elbow.axis"}
    assert res.method and res.settings["t_end"] == 0.5
