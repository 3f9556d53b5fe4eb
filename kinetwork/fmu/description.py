"""The FMU's XML: modelDescription.xml (FMI 2.0, Model Exchange and Co-Simulation) and
sources/buildDescription.xml (what FMPy and other tools compile the sources with)."""

import re
import xml.etree.ElementTree as ET

from .. import __version__
from .units import definition, fmi_name

#: the C sources of every FMU, in the order they are compiled
SOURCES = ("model.c", "kinetwork_fmi2.c")
#: log categories the runtime writes to
CATEGORIES = (("logEvents", "events: relations that change at time and state events"),
              ("logStatusError", "errors: why a call failed"))
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\[\d+(,\d+)*\])?")


def fmi_variable_name(name):
    """``name`` in FMI's structured naming: each dotted part an identifier (with indices, as
    ``probe.position[0]``) or quoted (``'my-part'``); ``der(x)`` of a state's name."""
    if name.startswith("der(") and name.endswith(")"):
        return f"der({fmi_variable_name(name[4:-1])})"
    parts = []
    for part in name.split("."):
        if _IDENTIFIER.fullmatch(part):
            parts.append(part)
        else:
            index = re.search(r"(\[\d+(,\d+)*\])$", part)
            body = part[:index.start()] if index else part
            body = body.replace("\\", "\\\\").replace("'", "\\'")
            parts.append(f"'{body}'" + (index.group(1) if index else ""))
    return ".".join(parts)


def _number(value):
    return repr(float(value))


def model_description(c, identifier, guid):
    """The text of modelDescription.xml for the Content ``c``."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": c.name, "guid": guid,
        "description": c.description, "generationTool": f"kinetwork {__version__}",
        "variableNamingConvention": "structured",
        "numberOfEventIndicators": str(c.n_indicators)})
    common = {"modelIdentifier": identifier, "canGetAndSetFMUstate": "true",
              "canSerializeFMUstate": "true", "providesDirectionalDerivative": "false",
              "canNotUseMemoryManagementFunctions": "false"}
    me = ET.SubElement(root, "ModelExchange", {**common,
                                               "completedIntegratorStepNotNeeded": "true"})
    cs = ET.SubElement(root, "CoSimulation", {
        **common, "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "false", "maxOutputDerivativeOrder": "0",
        "canRunAsynchronuously": "false"})
    for element in (me, cs):
        files = ET.SubElement(element, "SourceFiles")
        for name in SOURCES:
            ET.SubElement(files, "File", {"name": name})
    _units(root, c)
    cats = ET.SubElement(root, "LogCategories")
    for name, text in CATEGORIES:
        ET.SubElement(cats, "Category", {"name": name, "description": text})
    ex = c.experiment
    ET.SubElement(root, "DefaultExperiment", {
        "startTime": "0.0", "stopTime": _number(ex["t_end"]),
        "tolerance": _number(c.tolerance), "stepSize": _number(ex["step"])})
    variables = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(c.variables):
        attrs = {"name": fmi_variable_name(v.name), "valueReference": str(vr),
                 "causality": v.causality, "variability": v.variability}
        if v.description:
            attrs["description"] = v.description
        if v.initial is not None and v.causality != "input":
            attrs["initial"] = v.initial
        sv = ET.SubElement(variables, "ScalarVariable", attrs)
        real = {}
        if v.derivative is not None:
            real["derivative"] = str(c.states[v.derivative] + 1)
        if v.start is not None:
            real["start"] = _number(v.start)
        if v.unit and fmi_name(v.unit) not in ("", "1"):
            real["unit"] = fmi_name(v.unit)
        if v.nominal is not None:
            real["nominal"] = _number(v.nominal)
        if v.min is not None:
            real["min"] = _number(v.min)
        if v.max is not None:
            real["max"] = _number(v.max)
        ET.SubElement(sv, "Real", real)
    structure = ET.SubElement(root, "ModelStructure")
    outputs = ET.SubElement(structure, "Outputs") if len(c.outputs) else None
    for k in c.outputs:
        ET.SubElement(outputs, "Unknown", _unknown(k, c.variables[k].dependencies))
    derivatives = ET.SubElement(structure, "Derivatives") if len(c.rates) else None
    for k in c.rates:
        ET.SubElement(derivatives, "Unknown", _unknown(k, c.variables[k].dependencies))
    initial = sorted(k for k, v in enumerate(c.variables)
                     if v.initial == "calculated" and v.causality in ("output", "local"))
    if initial:
        unknowns = ET.SubElement(structure, "InitialUnknowns")
        for k in initial:           # depends on every known (parameters, exact starts)
            ET.SubElement(unknowns, "Unknown", {"index": str(k + 1)})
    ET.indent(root, "  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode")


def _unknown(k, dependencies):
    attrs = {"index": str(k + 1)}
    if dependencies is not None:
        attrs["dependencies"] = " ".join(str(d + 1) for d in dependencies)
    return attrs


def _units(root, c):
    """UnitDefinitions: every unit a variable has, with its SI base units where pint reads
    it."""
    names = {}
    for v in c.variables:
        name = fmi_name(v.unit) if v.unit else ""
        if name and name != "1":
            names.setdefault(name, v.unit)
    if not names:
        return
    units = ET.SubElement(root, "UnitDefinitions")
    for name in sorted(names):
        unit = ET.SubElement(units, "Unit", {"name": name})
        found = definition(names[name])
        if found is not None:
            factor, exponents = found
            attrs = {k: str(e) for k, e in exponents.items() if e}
            if factor != 1.0:
                attrs["factor"] = _number(factor)
            ET.SubElement(unit, "BaseUnit", attrs)


def build_description(identifier):
    """The text of sources/buildDescription.xml: one configuration, every source in C99."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    config = ET.SubElement(root, "BuildConfiguration", {
        "modelIdentifier": identifier,
        "description": "kinetwork's runtime and the model's CasADi code; link with libm"})
    files = ET.SubElement(config, "SourceFileSet", {"language": "C99"})
    for name in SOURCES:
        ET.SubElement(files, "SourceFile", {"name": name})
    ET.SubElement(config, "Library", {"name": "m", "external": "true",
                                       "description": "the C math library"})
    ET.indent(root, "  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode")
