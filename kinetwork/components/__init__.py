"""Component libraries; each module is one library of the file format's ``type`` names."""

from . import multibody, rotational, signals, translational
from .base import REGISTRY, Component, Param, Port, PortRef
from .probe import Probe

__all__ = ["REGISTRY", "Component", "Param", "Port", "PortRef", "Probe",
           "multibody", "rotational", "signals", "translational"]
