"""The package that runs a System was called ``kinetwork.simulation`` until it took the name the
layout gives it, ``kinetwork.solver``. Code written against the old name keeps working for a
release: ``kinetwork.simulation.driver`` and the rest are the ``kinetwork.solver`` modules
themselves (not copies), reached through a finder that aliases the names, with a
DeprecationWarning (a ``KinetworkDeprecationWarning``) on first use."""

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

from ..errors import KinetworkDeprecationWarning

_OLD, _NEW = __name__, __name__.rpartition(".")[0] + ".solver"

warnings.warn(KinetworkDeprecationWarning(
    f"{_OLD} is now {_NEW}; the old name goes in the next release",
    hint=f"import {_NEW} instead"), stacklevel=2)


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``kinetwork.simulation.X`` as the module ``kinetwork.solver.X``."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname.startswith(_OLD + "."):
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        return importlib.import_module(_NEW + spec.name[len(_OLD):])

    def exec_module(self, module):
        pass


if not any(isinstance(finder, _Alias) for finder in sys.meta_path):
    sys.meta_path.insert(0, _Alias())


def __getattr__(name):
    try:
        return importlib.import_module(f"{_NEW}.{name}")
    except ModuleNotFoundError:
        raise AttributeError(f"module {_OLD!r} has no attribute {name!r}") from None
