"""kn.fit recovers the seed's spring and damper from noisy probe data, within its intervals."""

import csv

import numpy as np
import pytest

import kinetwork as kn
from kinetwork import cli
from scenes import double_pendulum

TRUE = {"c": 2.5, "d": 0.4}
COLUMNS = ["probe1.angle", "probe2.angle"]


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    """The seed run at TRUE, each column with Gaussian noise of 1 % of its largest value,
    written as the CSV writer names columns."""
    res = kn.simulate(double_pendulum(), t_end=3.0, n_points=61, rtol=1e-10, atol=1e-12,
                      params=TRUE, jit=False)
    rng = np.random.default_rng(17)
    table = [res.t] + [res[c] + 0.01 * np.max(np.abs(res[c])) * rng.standard_normal(len(res.t))
                       for c in COLUMNS]
    path = tmp_path_factory.mktemp("fit") / "measured.csv"
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["t"] + COLUMNS)
        writer.writerows(np.column_stack(table).tolist())
    return path


def test_fit_recovers_c_and_d_within_the_95_percent_intervals(measured):
    model = double_pendulum()                 # starts from c = d = 1
    result = kn.fit(model, data=measured, params={"c": (0, 10), "d": (0, 10)})
    assert result.success and result.columns == COLUMNS and result.n_data == 61
    for name, true in TRUE.items():
        low, high = result.interval[name]
        assert low < true < high, (name, result.interval[name])
        # the intervals are informative: 1 % noise pins the parameters to about a percent
        assert high - low < 0.05 * true
    assert model.parameters["c"] == 1.0       # the model is not changed


def test_fit_from_the_command_line(measured, seed_file, capsys):
    assert cli.main(["fit", str(seed_file), "--data", str(measured), "--fit", "c=0:10",
                     "--fit", "d=0:10"]) == 0
    text = capsys.readouterr().out
    assert "95 % interval" in text and text.splitlines()[1].startswith("c ")


def test_bad_data_is_refused_by_name(measured, tmp_path):
    model = double_pendulum()
    with pytest.raises(kn.ModelError, match="columns: 'probe1.angel' is not in the data"):
        kn.fit(model, measured, {"c": (0, 10)}, columns=["probe1.angel"])
    with pytest.raises(kn.ModelError, match="params.c: the low bound 5 must be below"):
        kn.fit(model, measured, {"c": (5, 1)})
    bad = tmp_path / "bad.csv"
    bad.write_text("time,probe1.angle\n0,1\n1,2\n")
    with pytest.raises(kn.ModelError, match="no column 't'"):
        kn.fit(model, bad, {"c": (0, 10)})
