"""Component libraries; each module is one library of the file format's ``type`` names."""

from . import electrical, multibody, rotational, signals, translational
from .base import REGISTRY, Component, Param, Port, PortRef
from .probe import Probe

__all__ = ["REGISTRY", "Component", "Param", "Port", "PortRef", "Probe",
           "electrical", "multibody", "rotational", "signals", "translational"]
