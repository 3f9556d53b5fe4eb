"""Component libraries; each module is one library of the file format's ``type`` names."""

from . import electrical, multibody, rolling, rotational, signals, tables, translational
from .base import REGISTRY, Component, Param, Port, PortRef
from .probe import Probe

# A library's parts written in modules of their own (rolling contact needs multibody's joints,
# so multibody cannot import it back) are reachable from the library's module all the same:
# kn.multibody.RollingWheel.
_LIBRARIES = {"electrical": electrical, "multibody": multibody, "rotational": rotational,
              "signals": signals, "translational": translational}
for _type, _cls in REGISTRY.items():
    _library, _, _name = _type.rpartition(".")
    if _library in _LIBRARIES and not hasattr(_LIBRARIES[_library], _name):
        setattr(_LIBRARIES[_library], _name, _cls)
del _type, _cls, _library, _name

__all__ = ["REGISTRY", "Component", "Param", "Port", "PortRef", "Probe",
           "electrical", "multibody", "rotational", "signals", "translational"]
