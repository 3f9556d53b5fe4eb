"""A sweep's Dataset is built without importing dask.array (0.5 s, 4.7 s on a loaded machine,
for arrays that are numpy's), and xarray still knows a dask array made afterwards."""

import subprocess
import sys
import textwrap

import pytest


def test_a_threaded_sweep_imports_no_dask_array_and_dask_arrays_work_after():
    pytest.importorskip("dask.array")
    script = textwrap.dedent("""
        import sys
        import kinetwork as kn
        model = kn.load(sys.argv[1])
        ds = kn.sweep(model, {"c": [1.0, 2.0]}, t_end=0.5, n_points=11, progress=False)
        assert float(ds["probe1.angle"].sel(c=2.0)[-1]) != float(ds["probe1.angle"].sel(c=1.0)[-1])
        assert "dask.array" not in sys.modules, "dask.array imported"
        import dask.array as da
        import xarray as xr
        lazy = xr.DataArray(da.zeros((4, 3), chunks=2), dims=("a", "b"))
        assert lazy.chunks == ((2, 2), (2, 1))              # still a dask array to xarray
        print("ok")
    """)
    from kinetwork.examples import path
    out = subprocess.run([sys.executable, "-c", script, str(path("double_pendulum"))],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "ok"
