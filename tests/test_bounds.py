"""Every input does bounded work: units whose powers would take forever to compute, expressions
nested past Python's recursion limit, subsystems whose flat form grows without bound, too many
components, connections, problems, members or frames. Each is refused with a ModelError naming
its place, quickly: CPU time is bounded with a wide margin (never wall time)."""

import json
import time

import numpy as np
import pytest
from conftest import double_pendulum

import kinetwork as kn
from kinetwork.errors import MAX_PROBLEMS, SHOWN_PROBLEMS
from kinetwork.graph import subsystem
from kinetwork.graph.subsystem import MAX_COMPONENTS, flat_size

#: CPU seconds a refusal may take at most: far above what it takes (milliseconds), far below
#: what the unbounded work took (minutes to forever)
CPU_MARGIN = 20.0


class cpu_bound:
    """Within: at most CPU_MARGIN seconds of this process's CPU time."""

    def __enter__(self):
        self.start = time.process_time()

    def __exit__(self, *exc):
        used = time.process_time() - self.start
        assert used < CPU_MARGIN, f"{used:.1f} s of CPU"


TOWERS = ["1 kg^100^100^100", "1 kg*(km/m)^(100*100*100*100)", "1 kg*(km/m)^(100^100)",
          "1 kg*((km/m)^100)^100^100", "1 km⁹⁹⁹⁹⁹⁹⁹⁹", "2 kg**(10**10)"]


# -- units ------------------------------------------------------------------------------------
@pytest.mark.parametrize("text", TOWERS)
def test_a_power_tower_in_a_unit_is_refused_at_once_everywhere(text):
    with cpu_bound():
        with pytest.raises(kn.ModelError, match=r"beyond|digits"):
            kn.multibody.RigidBody("b", mass=text)
        with pytest.raises(kn.ModelError, match=r"parameters\.m1 .*(beyond|digits)"):
            kn.Model("m", parameters={"m1": text})
        data = json.loads(kn.dumps(double_pendulum()))
        data["parameters"]["m1"] = text
        with pytest.raises(kn.ModelError, match=r"parameters\.m1"):
            kn.loads(json.dumps(data))
        system = double_pendulum().compile()
        with pytest.raises(kn.ModelError, match=r"params\.m1"):
            kn.simulate(system, t_end=0.1, params={"m1": text})


@pytest.mark.parametrize("text, value", [
    ("2 kg", 2.0), ("500 g", 0.5), ("1 kg*m^2/m^2", 1.0), ("3 kg*(km/m)^2/(10^3)^2", 3.0),
    ("1 kg*m^(1/2)/m^(1/2)", 1.0), ("1 lb", 0.45359237), ("5 kg*(m/m)^100", 5.0),
])
def test_units_with_powers_in_range_still_convert_exactly(text, value):
    assert kn.multibody.RigidBody("b", mass=text).mass == pytest.approx(value, rel=1e-15)


# -- expressions ----------------------------------------------------------------------------
def definition(value):
    inner = kn.Model("inner", parameters={"L": 1.0})
    inner.add(kn.multibody.FixedTranslation("t", r=["L", 0, 0]))
    inner.expose("frame_a", "t.frame_a")
    outer = kn.Model("outer", parameters={"a": 1.0})
    outer.add(kn.multibody.Ground("g"))
    outer.add(kn.Subsystem("s", inner, params={"L": value}))
    outer.connect("g.frame", "s.frame_a")
    return outer


@pytest.mark.parametrize("minuses", [900, 5000])
def test_an_expression_nested_past_the_limit_is_refused_not_a_recursion_error(minuses):
    with cpu_bound(), pytest.raises(kn.ModelError, match="nested too deeply|longer than"):
        definition("-" * minuses + "a").validate()


def test_subsystem_expressions_that_grow_through_the_levels_are_refused():
    """Each level feeds its inner parameter the sum of its own twice: the text doubles at
    every level (2^30 characters at 30), refused once it passes what an expression may be."""
    model = kn.Model("leaf", parameters={"p": 1.0})
    model.add(kn.signals.Constant("k", k="p"))
    model.expose("y", "k.y")
    for level in range(30):
        outer = kn.Model(f"level{level}", parameters={"p": 1.0})
        outer.add(kn.Subsystem("s", model, params={"p": "p + p"}))
        outer.expose("y", "s.y")
        model = outer
    with cpu_bound(), pytest.raises(kn.ModelError, match="characters|nested too deeply") as info:
        model.flat()
    # the place where it grows too long, by its path in the flat model and in its file
    assert str(info.value).startswith("s.s.s.s.s.s.s.s.s.p (s.p): expression 'p + p' grows")


# -- subsystems, components, connections, problems ------------------------------------------
def doubling_file(levels):
    """A version-2 file whose definitions each place two of the next (2^levels leaves)."""
    defs = {f"D{i}": {"components": [{"name": "a", "type": f"D{i + 1}"},
                                     {"name": "b", "type": f"D{i + 1}"}]}
            for i in range(levels)}
    defs[f"D{levels}"] = {"components": [{"name": "x", "type": "signals.Constant",
                                          "params": {"k": 1.0}}]}
    return json.dumps({"format": "kinetwork.model", "version": 2, "name": "bomb",
                       "definitions": defs, "components": [{"name": "top", "type": "D0"}]})


def test_a_small_file_that_expands_without_bound_is_refused_before_expansion():
    text = doubling_file(25)
    assert len(text) < 9000
    with cpu_bound(), pytest.raises(kn.ModelError) as info:
        kn.loads(text)
    message = str(info.value)
    assert f"{2**25} components once its subsystems are expanded, more than the " \
           f"{MAX_COMPONENTS}" in message
    assert "top (D0, 33554432 components), top.a (D1, 16777216 components)" in message


def chain_file(levels):
    """A version-2 file whose definitions each place the next, ``levels`` deep."""
    defs = {f"D{i}": {"components": [{"name": "a", "type": f"D{i + 1}"}]}
            for i in range(levels)}
    defs[f"D{levels}"] = {"components": [{"name": "x", "type": "signals.Constant",
                                          "params": {"k": 1.0}}]}
    return json.dumps({"format": "kinetwork.model", "version": 2, "name": "deep",
                       "definitions": defs, "components": [{"name": "top", "type": "D0"}]})


def test_definitions_nested_past_the_limit_are_refused_once_not_at_every_level():
    # 3000 levels were 2971 problems in a 12 KB message, the deepest a RecursionError
    with pytest.raises(kn.ModelError) as info:
        kn.loads(chain_file(3000))
    assert str(info.value) == (f"definitions nested more than {subsystem.DEPTH_LIMIT} deep: "
                               f"D0 places D1 places D2 places ... places "
                               f"D{subsystem.DEPTH_LIMIT}")
    assert len(kn.loads(chain_file(subsystem.DEPTH_LIMIT - 2)).flat().components) == 1


@pytest.mark.parametrize("levels", [0, 3, 8])
def test_the_flat_size_counted_per_definition_is_the_size_of_the_flat_model(levels):
    model = kn.loads(doubling_file(levels), validate=False)
    flat = model.flat()
    assert flat_size(model) == (len(flat.components), len(flat.connections))


def test_a_model_holds_at_most_max_components(monkeypatch):
    monkeypatch.setattr(subsystem, "MAX_COMPONENTS", 50)
    import kinetwork.graph.model as graph_model
    monkeypatch.setattr(graph_model, "MAX_COMPONENTS", 50)
    m = kn.Model("many")
    for i in range(50):
        m.add(kn.signals.Constant(f"c{i}", k=1.0))
    with pytest.raises(kn.ModelError, match="has 50 components already"):
        m.add(kn.signals.Constant("one_more", k=1.0))
    assert len(m.components) == 50


def test_a_file_with_too_many_components_is_refused_before_any_is_built(monkeypatch):
    import kinetwork.graph.sections as sections         # reads a file's components
    monkeypatch.setattr(sections, "MAX_COMPONENTS", 50)
    built = []
    monkeypatch.setattr(sections, "_component", lambda *args: built.append(1))
    text = json.dumps({"format": "kinetwork.model", "version": 1, "name": "many",
                       "components": [{"name": f"c{i}", "type": "Probe"} for i in range(51)]})
    with pytest.raises(kn.ModelError, match="51 entries, more than the 50"):
        kn.loads(text)
    assert not built


@pytest.mark.parametrize("where", ["", "definitions.D."])
def test_a_large_file_is_counted_before_it_is_read_object_by_object(monkeypatch, where):
    import kinetwork.graph.io as io
    monkeypatch.setattr(io, "MAX_CONNECTIONS", 50)
    read = []
    monkeypatch.setattr(io.JSONObject, "from_pairs", lambda pairs: read.append(1))
    pairs = [[f"c{i}.y", f"c{i}.u"] for i in range(51)]
    data = {"format": "kinetwork.model", "version": 2, "name": "many", "components": [],
            "connections": [], "notes": "x" * io.COUNT_FIRST}
    if where:
        data["definitions"] = {"D": {"components": [], "connections": pairs}}
    else:
        data["connections"] = pairs
    with pytest.raises(kn.ModelError) as info:
        kn.loads(json.dumps(data))
    assert str(info.value) == f"{where}connections: 51 entries, more than the 50 a model " \
                              f"may have"
    assert not read


def test_a_flood_of_problems_is_counted_and_summarised():
    m = kn.Model("probes")
    for i in range(3000):
        m.add(kn.Probe(f"p{i}"))                  # each wired to nothing: one problem each
    with cpu_bound(), pytest.raises(kn.ModelError) as info:
        m.validate()
    err = info.value
    assert err.count == 3000 and len(err.problems) == MAX_PROBLEMS
    lines = str(err).splitlines()
    assert lines[0] == "3000 problems:" and len(lines) == SHOWN_PROBLEMS + 2
    assert lines[-1].startswith(f"  ... and {3000 - SHOWN_PROBLEMS} more")


def test_content_keys_of_nested_definitions_cost_their_number_not_their_instances():
    model = kn.loads(doubling_file(40), validate=False)      # 2^40 instances once flat
    with cpu_bound():
        first, second = model.content_key(), model.content_key()
    assert first == second and hash(first) == hash(second)


# -- outputs, members, frames -----------------------------------------------------------------
def test_the_memory_of_a_run_is_estimated_before_it_is_built(seed_file, monkeypatch):
    import kinetwork.graph.model as graph_model

    def refuse(*args, **kwargs):
        raise AssertionError("the equations were built")
    model = kn.load(seed_file)
    system = model.compile()
    upcall = graph_model.upcall            # Model.compile reaches the equations through it
    monkeypatch.setattr(graph_model, "upcall",
                        lambda name: refuse if name == "compile" else upcall(name))
    with cpu_bound(), pytest.raises(kn.ModelError, match=r"would need about .* GiB, more "
                                                         r"than the 2 GiB"):
        kn.simulate(system, n_points=20_000_000)
    with pytest.raises(kn.ModelError, match="3 runs"):
        kn.simulate(system, n_points=5_000_000, error_estimate=True)


@pytest.mark.parametrize("grid, says", [
    ({"d": [0.1] * 1001, "c": [1.0] * 1000}, r"1e\+06 members, more than"),
    ({"d": list(range(2000))}, "GiB, more than the 2 GiB"),
])
def test_a_sweep_is_bounded_before_any_member_runs(seed_model, grid, says):
    with cpu_bound(), pytest.raises(kn.ModelError, match=says):
        kn.sweep(seed_model, grid, n_points=200_000, progress=False)


@pytest.mark.parametrize("kwargs, says", [
    ({"gif": "a.gif", "fps": 1000}, "at most 50 frames per second"),
    ({"mp4": "a.mp4", "fps": 50}, "more than the 36000 an MP4 may have"),
])
def test_videos_are_bounded_in_frames_before_anything_is_drawn(seed_model, tmp_path,
                                                                 monkeypatch, kwargs, says):
    res = kn.simulate(seed_model, t_end=1000.0, n_points=101)
    monkeypatch.chdir(tmp_path)
    with cpu_bound(), pytest.raises(kn.ModelError, match=says):
        res.animate(**kwargs)
    assert list(tmp_path.iterdir()) == []


def test_an_animation_of_a_dense_run_computes_poses_only_where_its_frames_fall(
        seed_model, monkeypatch):
    from kinetwork.animation import scene
    res = kn.simulate(seed_model, t_end=10.0, n_points=100_001)
    evaluated = []
    poses = scene._frame_poses
    monkeypatch.setattr(scene, "_frame_poses",
                        lambda system, t, *rest: evaluated.append(len(t)) or
                        poses(system, t, *rest))
    anim = scene.animation_data(res, fps=30)
    assert len(anim["t"]) == 301 and evaluated[0] <= 2 * 301   # the neighbours of each frame
    monkeypatch.setattr(scene, "_between", lambda t, fps: slice(None))
    every = scene.animation_data(res, fps=30)                 # poses at all 100 001 points
    assert evaluated[-1] == 100_001
    for a, b in zip(anim["frames"], every["frames"]):
        np.testing.assert_allclose(a["position"], b["position"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(a["quaternion"], b["quaternion"], rtol=0, atol=1e-12)
