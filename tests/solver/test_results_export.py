"""Results where users work: pandas, xarray and a notebook's rich display, read back against
the arrays the results hold."""

import numpy as np
import pytest

import kinetwork as kn
from scenes import double_pendulum


@pytest.fixture(scope="module")
def results():
    m = double_pendulum()
    m.add(kn.Probe("tip", quantities=["position", "orientation"]))
    m.connect("tip.port", "elbow.frame_b")
    return kn.simulate(m, t_end=0.5, n_points=26)


def test_to_pandas_columns_index_and_units(results):
    df = results.to_pandas()
    header, data = results.columns()
    assert list(df.columns) == header[1:]
    assert df.index.name == "t"
    np.testing.assert_array_equal(df.index.to_numpy(), results.t)
    np.testing.assert_array_equal(df["probe1.angle"].to_numpy(), results["probe1.angle"])
    np.testing.assert_array_equal(df["tip.position[2]"].to_numpy(), results["tip.position"][:, 2])
    np.testing.assert_array_equal(df["tip.orientation[1,2]"].to_numpy(),
                                  results["tip.orientation"][:, 1, 2])
    units = df.attrs["units"]
    assert units["probe1.torque"] == "N*m" and units["tip.position[0]"] == "m"
    assert df.attrs["rtol"] == results.settings["rtol"]
    with_states = results.to_pandas(states=True)
    for name in results.state_names:
        np.testing.assert_array_equal(with_states[name].to_numpy(), results[name])


def test_to_xarray_dims_and_attrs(results):
    ds = results.to_xarray()
    assert ds["t"].attrs["units"] == "s"
    np.testing.assert_array_equal(ds["probe2.speed"].values, results["probe2.speed"])
    assert ds["probe2.speed"].attrs == {"units": "rad/s", "probe": "probe2",
                                        "quantity": "speed", "port": "elbow.axis"}
    assert ds["tip.position"].dims == ("t", "axis")
    assert list(ds["axis"].values) == ["x", "y", "z"]
    np.testing.assert_array_equal(ds["tip.position"].sel(axis="y").values,
                                  results["tip.position"][:, 1])
    assert ds["tip.orientation"].dims == ("t", "row", "col")
    assert float(ds["tip.orientation"].sel(row=2, col=3)[-1]) == \
        results["tip.orientation"][-1, 1, 2]
    assert ds.attrs["method"] == results.method


def test_notebook_display_has_summary_table_and_plot(results):
    page = results._repr_html_()
    assert "<table>" in page and "<svg" in page
    assert "<code>probe1.torque</code></td><td>N*m</td>" in page
    assert results.summary().splitlines()[0] == repr(results)
