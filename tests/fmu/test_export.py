"""FMU export checked by another engine: FMPy validates each FMU (``validate_fmu``) and runs
it, Model Exchange under its own CVode and Co-Simulation under the FMU's embedded
Dormand-Prince 5(4), and the probes must match ``kn.simulate`` within 1e-6 of each column's
scale; a parameter set through FMPy's ``start_values`` moves the answer as ``params=`` does,
an input set through FMPy's ``input`` as the block's value does. The models: the seed
(double pendulum), the four-bar (projected loops), arm_pid (blocks), drive_train (1-D
network) and a DC motor (circuit, an Input for its voltage) turning the double pendulum.

Each FMU is compiled once per module (a few seconds of gcc each)."""

import pathlib
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.fmu.build import _suffix
from kinetwork.fmu.content import content

fmpy = pytest.importorskip("fmpy", reason="the 'fmu' extra (fmpy) is not installed")
from fmpy.validation import validate_fmu  # noqa: E402

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
SUFFIX = _suffix()
#: each column of the FMU's results within this fraction of the column's largest value
TOL = 1e-6


def dc_motor_drive():
    """The double pendulum's shoulder turned by a DC motor whose voltage is an Input."""
    m = kn.load(MODELS / "double_pendulum.json")
    m.name = "dc_motor_drive"
    E = kn.electrical
    m.parameters["R_a"] = 1.2
    m.add(kn.signals.Input("voltage", value="12*min(t/0.1, 1)"))
    m.add(E.VoltageSource("src"))
    m.add(E.DCMotor("motor", R="R_a", L=0.05, k=0.3, J=2e-3))
    m.add(E.Ground("gnd"))
    m.add(kn.Probe("armature", quantities=["current"]))
    m.connect("voltage.y", "src.u")
    m.connect("src.p", "motor.p")
    m.connect("motor.n", "src.n")
    m.connect("gnd.p", "src.n")
    m.connect("motor.flange", "shoulder.axis")
    m.connect("motor.support", "shoulder.support")
    m.connect("armature.port", "motor.p")
    m.simulation["t_end"] = 2.0
    return m


CASES = {
    "double_pendulum": (lambda: kn.load(MODELS / "double_pendulum.json"), "L1"),
    "fourbar": (lambda: kn.load(MODELS / "fourbar.json"), "a"),
    "arm_pid": (lambda: kn.load(MODELS / "arm_pid.json"), "L1"),
    "drive_train": (lambda: kn.load(MODELS / "drive_train.json"), "c"),
    "dc_motor_drive": (dc_motor_drive, "R_a"),
}


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    out = {}
    for name, (make, _) in CASES.items():
        model = make()
        out[name] = (model, kn.export_fmu(model, folder / f"{name}.fmu"))
    return out


def reference(model, params=None, **kw):
    res = kn.simulate(model, params=params or {}, **kw)
    header, data = res.columns()
    return res.t, dict(zip(header[1:], data[:, 1:].T))


def run_fmu(path, kind, t, **kw):
    return fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=float(t[-1]),
                             output_interval=float(t[1] - t[0]), **kw)


def worst(t, ref, res):
    """(largest error over each column's scale, its column); every probe column present."""
    assert set(res.dtype.names[1:]) == set(ref)
    errors = {}
    for col, values in ref.items():
        got = np.interp(t, res["time"], res[col])
        errors[col] = np.max(np.abs(got - values)) / max(np.max(np.abs(values)), 1e-12)
    col = max(errors, key=errors.get)
    return errors[col], col


@pytest.mark.parametrize("name", list(CASES))
def test_fmpy_validates(exported, name):
    assert validate_fmu(str(exported[name][1])) == []


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("name", list(CASES))
def test_matches_simulate(exported, name, kind):
    model, path = exported[name]
    t, ref = reference(model)
    res = run_fmu(path, kind, t)
    assert res["time"][-1] == pytest.approx(t[-1])
    err, col = worst(t, ref, res)
    assert err < TOL, f"{name} {kind}: {col} off by {err:.3g} of its scale"


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("name", list(CASES))
def test_parameter_through_fmpy(exported, name, kind):
    """A parameter changed by FMPy's start_values: the answer params= gives, not the old."""
    model, path = exported[name]
    key = CASES[name][1]
    changed = {key: 1.25 * model.parameters[key]}
    t, before = reference(model)
    t, ref = reference(model, changed)
    res = run_fmu(path, kind, t, start_values=changed)
    err, col = worst(t, ref, res)
    assert err < TOL, f"{name} {kind} {changed}: {col} off by {err:.3g} of its scale"
    moved = max(np.max(np.abs(ref[c] - before[c])) / max(np.max(np.abs(ref[c])), 1e-12)
                for c in ref)
    assert moved > 1e3 * TOL         # the change is seen, far beyond the tolerance


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_input_through_fmpy(exported, kind):
    """The motor's voltage set through the FMU's input (6 V, where the block's own value
    ramps to 12 V) gives the run of the model whose Input block has that value. Constant:
    Co-Simulation holds an input over a communication step, as FMI 2.0 says, and FMPy's
    CVode does not apply a varying input inside its steps."""
    model, path = exported["dc_motor_drive"]
    driven = dc_motor_drive()
    driven.components["voltage"]._values["value"] = 6.0
    t, ref = reference(driven)
    signal = np.array([(0.0, 6.0), (float(t[-1]), 6.0)],
                      dtype=[("time", float), ("voltage", float)])
    res = run_fmu(path, kind, t, input=signal)
    err, col = worst(t, ref, res)
    assert err < TOL, f"{kind}: {col} off by {err:.3g} of its scale"
    own = run_fmu(path, kind, t)
    assert np.max(np.abs(own["armature.current"] - res["armature.current"])) > 1.0


def description(path):
    with zipfile.ZipFile(path) as z:
        return ET.fromstring(z.read("modelDescription.xml")), z.namelist()


def test_what_maps_to_what(exported):
    """Parameters tunable with their units, the Input an input, probes outputs (vectors as
    [0], [1], [2]), each state's rate declared, units defined in SI base units; the binary
    for this platform and the sources with their build description."""
    root, names = description(exported["dc_motor_drive"][1])
    variables = root.find("ModelVariables").findall("ScalarVariable")
    by_name = {v.get("name"): v for v in variables}
    r_a = by_name["R_a"]
    assert (r_a.get("causality"), r_a.get("variability")) == ("parameter", "tunable")
    assert r_a.find("Real").get("unit") == "Ohm"
    assert float(r_a.find("Real").get("start")) == 1.2
    assert by_name["voltage"].get("causality") == "input"
    assert by_name["armature.current"].get("causality") == "output"
    assert by_name["motor.La.i"].find("Real").get("unit") == "A"
    assert by_name["der(shoulder.qd)"].find("Real").get("unit") == "rad/s2"
    states = [v for v in variables if v.get("description") == "state"]
    rates = [v for v in variables if v.find("Real").get("derivative")]
    assert len(states) == len(rates) == 5
    for rate in rates:
        state = variables[int(rate.find("Real").get("derivative")) - 1]
        assert rate.get("name") == f"der({state.get('name')})"
    units = {u.get("name"): u.find("BaseUnit") for u in root.find("UnitDefinitions")}
    assert units["Ohm"].attrib == {"kg": "1", "m": "2", "s": "-3", "A": "-2"}
    structure = root.find("ModelStructure")
    assert len(structure.find("Derivatives")) == 5
    assert len(structure.find("Outputs")) == sum(v.get("causality") == "output"
                                                 for v in variables)
    assert any(n.startswith("binaries/") and n.endswith("/dc_motor_drive" + SUFFIX)
               for n in names)
    for source in ("sources/model.c", "sources/kinetwork_fmi2.c", "sources/fmi2Functions.h",
                   "sources/buildDescription.xml"):
        assert source in names
    build = ET.fromstring(zipfile.ZipFile(exported["dc_motor_drive"][1]).read(
        "sources/buildDescription.xml"))
    assert [f.get("name") for f in build.iter("SourceFile")] == ["model.c",
                                                                 "kinetwork_fmi2.c"]


def test_vector_probes_as_columns():
    """A vector probe quantity is one output per component, named as the CSV names them."""
    model = kn.load(MODELS / "spring_pendulum.json")
    c = content(model)
    outputs = [c.variables[k].name for k in c.outputs]
    header = kn.simulate(model, t_end=0.01).columns()[0][1:]
    assert outputs == header
    assert "bob_probe.velocity[1]" in outputs


def test_guid_follows_content(tmp_path):
    """The same model gives the same GUID; another parameter value another."""
    model = kn.load(MODELS / "double_pendulum.json")
    one = description(kn.export_fmu(model, tmp_path / "a.fmu"))[0].get("guid")
    two = description(kn.export_fmu(model, tmp_path / "b.fmu"))[0].get("guid")
    model.parameters["L1"] = 1.5
    three = description(kn.export_fmu(model, tmp_path / "c.fmu"))[0].get("guid")
    assert one == two != three


def test_friction_refused_by_name(tmp_path):
    with pytest.raises(kn.ModelError, match="clutch, brake: friction and stops"):
        kn.export_fmu(kn.load(MODELS / "msl_friction.json"), tmp_path / "f.fmu")
    assert not (tmp_path / "f.fmu").exists()


def test_nothing_else_overwritten(tmp_path):
    mine = tmp_path / "notes.fmu"
    mine.write_text("my notes")
    with pytest.raises(kn.ModelError, match="not an FMU; not replaced"):
        kn.export_fmu(kn.load(MODELS / "double_pendulum.json"), mine)
    assert mine.read_text() == "my notes"
    with pytest.raises(kn.ModelError, match="ends in .fmu"):
        kn.export_fmu(kn.load(MODELS / "double_pendulum.json"), tmp_path / "out.zip")
    with pytest.raises(kn.ModelError, match="choose one of"):
        kn.export_fmu(kn.load(MODELS / "double_pendulum.json"), tmp_path / "o.fmu",
                      kind="fmi3")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.fmu"]


# FMPy's CVode calls the FMU from a ctypes callback, whose exception Python reports as
# unraisable before FMPy raises its own
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_dead_point_stops_the_fmu(tmp_path):
    """The five-revolute loop meets a dead point of its partition at t = 1.07 s, where
    kn.simulate re-partitions: the FMU, which keeps its partition, stops there with an error
    saying so, in Co-Simulation and under FMPy's CVode, rather than integrate on."""
    model = kn.load(MODELS / "five_revolute_loop.json")
    path = kn.export_fmu(model, tmp_path / "five.fmu")
    for kind in ("CoSimulation", "ModelExchange"):
        messages = []
        with pytest.raises(Exception):
            fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=1.5, output_interval=0.01,
                              logger=lambda *args: messages.append(args[-1]))
        words = b" ".join(m if isinstance(m, bytes) else str(m).encode() for m in messages)
        assert b"dead point" in words, kind
        assert b"t = 1.0" in words, kind


def test_rebuilt_from_its_sources(exported, tmp_path):
    """FMPy builds the binary again from sources/ and buildDescription.xml alone (CMake and
    this machine's compiler), and the rebuilt FMU gives the same answer."""
    build = pytest.importorskip("fmpy.build")
    import shutil
    if shutil.which("cmake") is None:
        pytest.skip("FMPy builds FMUs with CMake, which this machine lacks")
    model, path = exported["arm_pid"]
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(path) as z:
        z.extractall(folder)
    shutil.rmtree(folder / "binaries")
    (tmp_path / "build").mkdir()
    build.build_platform_binary(folder, build_dir=tmp_path / "build")
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as z:
        for file in folder.rglob("*"):
            if file.is_file():
                z.write(file, file.relative_to(folder).as_posix())
    assert any(n.startswith("binaries/") for n in zipfile.ZipFile(rebuilt).namelist())
    t, ref = reference(model)
    err, col = worst(t, ref, run_fmu(rebuilt, "CoSimulation", t))
    assert err < TOL, f"{col} off by {err:.3g} of its scale"


def test_command_line(tmp_path, capsys):
    """kinetwork export MODEL --fmu out.fmu writes a valid FMU; refuses, exit 1, to replace
    a file that is not one."""
    from kinetwork.cli import main
    out = tmp_path / "pendulum.fmu"
    assert main(["export", "double_pendulum", "--fmu", str(out), "--kind", "cs"]) == 0
    assert "wrote the FMU of double_pendulum" in capsys.readouterr().out
    assert validate_fmu(str(out)) == []
    root, _ = description(out)
    assert root.find("CoSimulation") is not None and root.find("ModelExchange") is None
    mine = tmp_path / "mine.fmu"
    mine.write_text("keep me")
    assert main(["export", "double_pendulum", "--fmu", str(mine)]) == 1
    assert "not an FMU; not replaced" in capsys.readouterr().err
    assert mine.read_text() == "keep me"
