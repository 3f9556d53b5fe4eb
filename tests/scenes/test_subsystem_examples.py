"""The subsystem examples of ``models/``: MSL's EngineV6 from one Cylinder definition placed
six times (``models/engine_v6``) and the seed arm with one Axis definition on each joint
(``models/robot``). Each gives the very numbers of the same scene written flat, and the files
in ``models/`` are what the builders write today."""

import pathlib

import numpy as np
import pytest

import kinetwork as kn
from close import assert_same_json_file, assert_same_numbers
from scenes import drives, engine

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


@pytest.fixture(scope="module")
def engines():
    """EngineV6 read from its files, and written flat by tests/scenes/engine.py."""
    return kn.load(MODELS / "engine_v6" / "EngineV6.json"), engine.build_engine_v6()


def test_engine_v6_of_one_cylinder_definition_is_the_flat_engine(engines):
    placed, flat = engines
    assert [c.name for c in placed.components.values() if isinstance(c, kn.Subsystem)] == \
        [f"cyl{i}" for i in range(1, 7)]
    a, b = placed.compile(loops="partition"), flat.compile(loops="partition")
    assert a.state_names == b.state_names == ["bearing.q", "bearing.qd", "filter1.x",
                                              "filter2.x"]
    assert a.algebraic_names[:3] == ["cyl1.b1.q", "cyl1.b2.q", "cyl1.cylinder.q"]
    kw = dict(t_end=0.05, n_points=51, rtol=1e-8, atol=1e-10, jit=False)
    ra, rb = kn.simulate(a, **kw), kn.simulate(b, **kw)
    assert np.max(np.abs(ra["crankshaft.angle"] - rb["crankshaft.angle"])) <= 1e-10
    # the same equations, step for step, but the files' tables were written on another machine
    # (their last digits are that machine's): equal to within what such digits move
    assert_same_numbers(ra.states, rb.states, rtol=1e-9)
    assert_same_numbers(ra["cyl3.piston_probe.position"], rb["cyl3_piston_probe.position"],
                        rtol=1e-9)
    assert ra["crankshaft.speed"][-1] > ra["crankshaft.speed"][0]      # the engine runs


def test_engine_v6_file_is_five_times_smaller_than_flat(engines, tmp_path):
    placed, flat = engines
    flat.save(tmp_path / "EngineV6_flat.json")
    flat_size = (tmp_path / "EngineV6_flat.json").stat().st_size
    size = (MODELS / "engine_v6" / "EngineV6.json").stat().st_size
    assert flat_size >= 5 * size, (flat_size, size)
    # with its Cylinder file beside it, or inline in one file, still a fraction of the flat
    together = size + (MODELS / "engine_v6" / "Cylinder.json").stat().st_size
    placed.save(tmp_path / "EngineV6_inline.json")
    inline = (tmp_path / "EngineV6_inline.json").stat().st_size
    assert flat_size >= 3 * max(together, inline), (flat_size, together, inline)


def test_the_arm_with_axis_subsystems_is_arm_pid():
    placed = kn.load(MODELS / "robot" / "arm_axes.json")
    flat = kn.load(MODELS / "arm_pid.json")
    ra, rb = kn.simulate(placed), kn.simulate(flat)
    assert_same_numbers(ra.states, rb.states)
    assert_same_numbers(ra["shoulder_axis.command.value"], rb["command_shoulder.value"])
    assert ra.state_names[4:6] == ["shoulder_axis.pid.x[0]", "shoulder_axis.pid.x[1]"]


@pytest.mark.parametrize("write, names", [
    (engine.write_models, ["EngineV6.json", "Cylinder.json"]),
    (drives.write_robot, ["arm_axes.json", "Axis.json"]),
], ids=["engine_v6", "robot"])
def test_the_example_files_are_what_the_builders_write(tmp_path, write, names):
    folder = MODELS / ("engine_v6" if "EngineV6.json" in names else "robot")
    write(tmp_path)
    for name in names:
        assert_same_json_file(tmp_path / name, folder / name)
