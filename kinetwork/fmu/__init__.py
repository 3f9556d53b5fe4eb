"""FMU export: a model as an FMI 2.0 Functional Mock-up Unit (Model Exchange and
Co-Simulation), for Simulink, Modelica tools, co-simulation masters and HIL rigs.

``kn.export_fmu(model, "model.fmu")`` or ``kinetwork export MODEL --fmu model.fmu``;
``content`` says what maps to what, ``description`` writes the XML, ``units`` the units,
``build`` writes and compiles it, ``command`` is the CLI's ``export``, and ``c/`` holds the
FMI runtime in C that every FMU is compiled with.
"""

from .build import export_fmu

__all__ = ["export_fmu"]
