"""Results CSV files that pandas reads as they are, their sidecar, and ``kn.read_csv``.

The table holds numbers only (a header row, then rows); what is not data (units, settings,
where a partial run stopped, where a write was cut) is in ``x.meta.json``, checked against the
table by its SHA-256 when read back.
"""

import json
import warnings

import numpy as np
import pandas as pd
import pytest
from conftest import double_pendulum

import kinetwork as kn
from kinetwork.solver.csvio import SidecarWarning, sidecar


def frame_model():
    """The seed with a frame probe: vector and orientation columns as well as scalars."""
    model = double_pendulum()
    model.add(kn.Probe("tip", quantities=["position", "orientation"]))
    model.connect("tip.port", "mass2.frame_a")
    return model


@pytest.fixture(scope="module")
def complete():
    return kn.simulate(frame_model(), t_end=0.5, n_points=51)


@pytest.fixture(scope="module")
def partial():
    with pytest.raises(kn.SimulationError) as err:
        kn.simulate(frame_model(), t_end=50.0, n_points=501, max_steps=3)
    assert err.value.results.partial is not None
    return err.value.results


@pytest.mark.parametrize("which", ["complete", "partial"])
def test_pandas_reads_every_column_as_numbers(which, request, tmp_path):
    res = request.getfixturevalue(which)
    res.to_csv(tmp_path / "out.csv")
    frame = pd.read_csv(tmp_path / "out.csv")
    assert list(frame.columns) == res.column_names()        # DESIGN.md's names, t first
    assert all(dtype == np.float64 for dtype in frame.dtypes), frame.dtypes
    assert len(frame) == len(res.t)
    np.testing.assert_allclose(frame.to_numpy(), res.columns()[1], rtol=1e-15, atol=0)


@pytest.mark.parametrize("which", ["complete", "partial"])
def test_read_csv_gives_back_the_results_with_units(which, request, tmp_path):
    res = request.getfixturevalue(which)
    res.to_csv(tmp_path / "out.csv")
    table = kn.read_csv(tmp_path / "out.csv")
    np.testing.assert_allclose(table.t, res.t, rtol=1e-15, atol=0)
    for name in res.signal_names:
        assert table[name].shape == res[name].shape
        np.testing.assert_allclose(table[name], res[name], rtol=1e-15, atol=0)
        assert table.units[name] == res.units[name]
    assert table.units["t"] == "s" and table.units["tip.position[1]"] == "m"
    assert table.units["probe1.angle"] == "rad" and table["tip.position[1]"].shape == res.t.shape
    assert table.settings["rtol"] == res.settings["rtol"]
    if which == "partial":
        assert table.status == "partial"
        assert table.partial == {"t_reached": res.partial["t_reached"],
                                 "reason": " ".join(res.partial["reason"].split())}
    else:
        assert table.status == "ok" and table.partial is None
    frame = table.to_pandas()
    assert frame.attrs["units"]["probe1.torque"] == "N*m" and frame.index.name == "t"


def test_the_sidecar_is_json_beside_the_table(complete, tmp_path):
    complete.to_csv(tmp_path / "run.csv")
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["format"] == "kinetwork.results" and meta["csv"]["rows"] == 51
    tip = next(s for s in meta["signals"] if s["name"] == "tip.orientation")
    assert tip["shape"] == [3, 3] and tip["port"] == "mass2.frame_a"
    assert tip["columns"][1] == "tip.orientation[0,1]"
    assert sidecar("a/b.CSV") == "a/b.meta.json" and sidecar("a.txt") == "a.txt.meta.json"


def test_a_table_changed_after_writing_is_read_without_its_stale_sidecar(complete, tmp_path):
    path = tmp_path / "out.csv"
    complete.to_csv(path)
    pd.read_csv(path).iloc[:10].to_csv(path, index=False)      # edited elsewhere
    with pytest.warns(SidecarWarning, match="describes another table"):
        table = kn.read_csv(path)
    assert len(table.t) == 10 and table.units["probe1.angle"] == "" and table.partial is None
    assert table["tip.position"].shape == (10, 3)               # grouped by the names alone


def test_a_csv_without_a_sidecar_reads(tmp_path):
    (tmp_path / "x.csv").write_text("t,a.angle,b.position[0],b.position[1]\n0,1,2,3\n1,4,5,6\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = kn.read_csv(tmp_path / "x.csv")
    np.testing.assert_array_equal(table["b.position"], [[2, 3], [5, 6]])
    assert table.units == {"t": "s", "a.angle": "", "b.position[0]": "", "b.position[1]": "",
                           "b.position": ""}


def test_the_older_trailer_still_reads(tmp_path):
    (tmp_path / "old.csv").write_text("t,a\n0.0,1.0\n0.5,2.0\n# partial: the run stopped at "
                                      "t = 0.5 s: too much work\n")
    table = kn.read_csv(tmp_path / "old.csv")
    assert table.status == "partial" and "too much work" in table.partial["reason"]
    np.testing.assert_array_equal(table["a"], [1.0, 2.0])


@pytest.mark.parametrize("text, match", [
    ("", "header must start with 't'"), ("x,y\n1,2\n", "header must start with 't'"),
    ("t,a\n0,1\n1\n", "row 3 has 1 values"), ("t,a\n0,abc\n", "row 2: not a number")])
def test_what_is_no_table_of_results_is_refused_by_name(tmp_path, text, match):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(kn.ModelError, match=match):
        kn.read_csv(tmp_path / "bad.csv")


def test_a_json_file_of_the_users_at_the_sidecars_place_is_not_replaced(complete, tmp_path):
    mine = tmp_path / "out.meta.json"
    mine.write_text('{"my": "notes"}\n')
    with pytest.raises(kn.ModelError, match="sidecar"):
        complete.to_csv(tmp_path / "out.csv")
    assert mine.read_text() == '{"my": "notes"}\n' and not (tmp_path / "out.csv").exists()
    complete.to_csv(tmp_path / "out.csv", overwrite=True)
    assert json.loads(mine.read_text())["format"] == "kinetwork.results"


def test_the_command_line_writes_both(tmp_path):
    from kinetwork.cli import main
    double_pendulum().save(tmp_path / "dp.json")
    assert main(["run", str(tmp_path / "dp.json"), "--t-end", "0.2", "--n-points", "21",
                 "--out", str(tmp_path / "o.csv"), "--quiet"]) == 0
    table = kn.read_csv(tmp_path / "o.csv")
    assert table.status == "ok" and table.units["probe1.speed"] == "rad/s"
    assert repr(table).startswith("<Table o.csv: 21 points")
