"""An ``xarray.Dataset`` of numpy arrays, built (and used after) without importing
``dask.array``.

xarray asks for dask.array's ``Array`` type each time it wraps an array (to tell a dask array
from a numpy one: building a Dataset, selecting from it, converting it), and when dask is
installed it imports dask.array to answer: 0.5 s, 4.7 s on a loaded machine, which the first
``kn.sweep`` of a process paid for numpy arrays. While dask.array is not imported no dask
array can exist, so the question has its answer without the import. Before its first Dataset,
kinetwork gives xarray's record of the dask module (``pycompat._cached_duck_array_modules``)
a type that answers exactly that: an object is a dask array when dask.array is imported and
the object is one of its arrays. Everything else about the record is dask's own (its version,
the module, imported when asked for). When xarray has its record already, or keeps it
elsewhere (another version), nothing is changed.
"""

import functools
import importlib
import importlib.metadata
import importlib.util
import sys


def dataset(data, coords, attrs):
    """``xarray.Dataset(data, coords=coords, attrs=attrs)`` of numpy arrays."""
    import xarray as xr
    _lazy_dask_record()
    return xr.Dataset(data, coords=coords, attrs=attrs)


class _DaskArrayType(type):
    def __instancecheck__(cls, obj):
        module = sys.modules.get("dask.array")
        return module is not None and isinstance(obj, module.Array)

    def __subclasscheck__(cls, sub):
        module = sys.modules.get("dask.array")
        return module is not None and issubclass(sub, module.Array)


class _DaskArray(metaclass=_DaskArrayType):
    """Stands for ``dask.array.Array`` in isinstance tests, without importing it."""


@functools.cache
def _lazy_dask_record():
    """Give xarray the record of dask described in the module's docstring, once."""
    try:
        from xarray.namedarray import pycompat
        cache, base, version = (pycompat._cached_duck_array_modules,
                                pycompat.DuckArrayModule, pycompat.Version)
    except (ImportError, AttributeError):
        return
    if "dask" in cache or "dask.array" in sys.modules or \
            importlib.util.find_spec("dask") is None:
        return

    class LazyDask(base):
        def __init__(self):           # not the base's: that imports dask.array
            self.version = version(importlib.metadata.version("dask"))
            self.type, self.available = (_DaskArray,), True

        @property
        def module(self):
            return importlib.import_module("dask")
    cache["dask"] = LazyDask()
