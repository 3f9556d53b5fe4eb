"""Wiring diagrams (kinetwork.diagram): the layered layout, the SVG, the CLI and Jupyter."""

import functools
import os
import pathlib
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

import kinetwork as kn
from kinetwork.cli import main
from kinetwork.diagram import auto_layout, svg

ROOT = pathlib.Path(__file__).resolve().parent.parent
MODELS = sorted(ROOT.glob("models/**/*.json"))
NS = "{http://www.w3.org/2000/svg}"
IDS = [str(p.relative_to(ROOT / "models")) for p in MODELS]


@functools.lru_cache(maxsize=None)
def drawn(path):
    """(model, svg text, parsed root) of an example, drawn once per test run."""
    model = kn.load(path, validate=False)
    text = svg(model)
    return model, text, ET.fromstring(text)


def blocks(root):
    """Block name -> (x, y, w, h)."""
    return {g.get("data-name"): tuple(float(g.get(f"data-{k}")) for k in "xywh")
            for g in root.iter(f"{NS}g") if g.get("class") == "block"}


def markers(root):
    """"comp.port" -> centre of its marker."""
    return {g.get("data-port"): (float(g.get("data-x")), float(g.get("data-y")))
            for g in root.iter(f"{NS}g") if g.get("class") == "port"}


def wires(root):
    """(from, to, corner points) of every wire; corners are the path's M, Q control points
    and final L."""
    out = []
    for path in root.iter(f"{NS}path"):
        if path.get("class") != "wire":
            continue
        d = path.get("d")
        number = r"(-?[\d.]+),(-?[\d.]+)"
        points = [re.match(rf"M{number}", d).groups(), *re.findall(rf"Q{number}", d),
                  re.findall(rf"L{number}", d)[-1]]
        out.append((path.get("data-from"), path.get("data-to"),
                    [(float(x), float(y)) for x, y in points]))
    return out


def overlap(a, b):
    (ax, ay, aw, ah), (bx, by, bw, bh) = a, b
    return ax < bx + bw and bx < ax + aw and ay < by + bh and by < ay + ah


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_every_example_draws_one_block_per_component_and_one_wire_per_connection(path):
    model, text, root = drawn(path)
    assert root.tag == f"{NS}svg"
    assert set(blocks(root)) == set(model.components)
    assert len(list(root.iter(f"{NS}g"))) >= len(model.components)
    pairs = sorted((a, b) for a, b, _ in wires(root))
    assert pairs == sorted((a.path, b.path) for a, b in model.connections)
    # the blocks are where auto_layout puts them
    layout = auto_layout(model)
    assert blocks(root) == {n: (s["x"], s["y"], s["w"], s["h"]) for n, s in layout.items()}


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_blocks_do_not_overlap(path):
    rects = list(blocks(drawn(path)[2]).items())
    clashes = [(a, b) for i, (a, ra) in enumerate(rects) for b, rb in rects[i + 1:]
               if overlap(ra, rb)]
    assert not clashes


@pytest.mark.parametrize("path", MODELS, ids=IDS)
def test_wires_end_on_their_ports_and_go_round_blocks(path):
    model, _, root = drawn(path)
    at, rects = markers(root), blocks(root)
    assert set(at) == {f"{name}.{port}" for name, c in model.components.items()
                       for port in c.ports}
    for a, b, points in wires(root):
        assert points[0] == pytest.approx(at[a], abs=0.06), a
        assert points[-1] == pytest.approx(at[b], abs=0.06), b
        for (x0, y0), (x1, y1) in zip(points, points[1:]):
            assert x0 == x1 or y0 == y1, f"{a} - {b}: not orthogonal"
            for name, (x, y, w, h) in rects.items():
                # a segment never runs through a block's inside (its ends sit on the edge)
                inside = (min(x0, x1) < x + w - 1 and max(x0, x1) > x + 1 and
                          min(y0, y1) < y + h - 1 and max(y0, y1) > y + 1)
                assert not inside, f"wire {a} - {b} crosses block {name}"


def test_the_layout_given_in_a_file_is_kept():
    model = kn.load(ROOT / "models" / "double_pendulum.json", validate=False)
    layout = auto_layout(model)
    assert {n: (s["x"], s["y"]) for n, s in layout.items()} == \
        {n: (s["x"], s["y"]) for n, s in model.layout.items()}
    assert all(s["w"] > 0 and s["h"] > 0 for s in layout.values())


def test_a_partial_layout_is_kept_and_the_rest_placed_around_it():
    model = kn.load(ROOT / "models" / "arm_pid.json", validate=False)
    given = dict(model.layout)
    assert 0 < len(given) < len(model.components)
    layout = auto_layout(model)
    assert set(layout) == set(model.components)
    for name, spot in given.items():
        assert (layout[name]["x"], layout[name]["y"]) == (spot["x"], spot["y"])
    rects = [(s["x"], s["y"], s["w"], s["h"]) for s in layout.values()]
    assert not any(overlap(a, b) for i, a in enumerate(rects) for b in rects[i + 1:])
    assert model.layout == given                  # auto_layout does not write to the model


def seed(layout=None):
    """The seed's double pendulum built in Python, with ``layout``."""
    model = kn.Model("seed")
    model.add(kn.multibody.Ground("ground"))
    model.add(kn.multibody.Revolute("shoulder", axis=[0, 0, 1]))
    model.add(kn.multibody.FixedTranslation("link1", r=[0, -1, 0]))
    model.add(kn.multibody.RigidBody("mass1", mass=1.0, r_cm=[0, -0.5, 0]))
    model.add(kn.multibody.Revolute("elbow", axis=[0, 0, 1]))
    model.add(kn.multibody.RigidBody("mass2", mass=1.0, r_cm=[0, -0.5, 0]))
    model.add(kn.rotational.SpringDamper("spring", c=1.0, d=1.0))
    model.add(kn.Probe("probe1", quantities=["angle"]))
    for a, b in [("ground.frame", "shoulder.frame_a"), ("shoulder.frame_b", "link1.frame_a"),
                 ("shoulder.frame_b", "mass1.frame_a"), ("link1.frame_b", "elbow.frame_a"),
                 ("elbow.frame_b", "mass2.frame_a"), ("spring.flange_a", "shoulder.support"),
                 ("spring.flange_b", "shoulder.axis"), ("probe1.port", "shoulder.axis")]:
        model.connect(a, b)
    model.layout = layout or {}
    return model


def test_the_layered_layout_follows_the_flow_and_stacks_parts_on_joints():
    layout = auto_layout(seed())
    x = {n: s["x"] for n, s in layout.items()}
    # frame_b to frame_a: one layer further right
    assert x["ground"] < x["shoulder"] < x["link1"] < x["elbow"] < x["mass2"]
    assert x["shoulder"] < x["mass1"]
    # the spring-damper on the shoulder's support and axis stands above it, in its column
    spring, shoulder = layout["spring"], layout["shoulder"]
    assert spring["y"] + spring["h"] < shoulder["y"]
    assert spring["x"] < shoulder["x"] + shoulder["w"] and shoulder["x"] < spring["x"] + spring["w"]


def test_positions_from_python_are_kept_and_odd_entries_ignored():
    model = seed({"ground": {"x": -300, "y": 40.5}, "link1": {"x": "far"}, "mass2": [1, 2]})
    layout = auto_layout(model)
    assert (layout["ground"]["x"], layout["ground"]["y"]) == (-300, 40.5)
    assert svg(model).startswith("<svg")


def test_the_same_model_gives_the_same_drawing_in_every_process():
    model = kn.load(ROOT / "models" / "engine_v6" / "EngineV6.json", validate=False)
    assert svg(model) == svg(model)
    assert auto_layout(model) == auto_layout(kn.load(ROOT / "models" / "engine_v6" /
                                                      "EngineV6.json", validate=False))
    code = ("import sys, kinetwork as kn; from kinetwork.diagram import svg; "
            "sys.stdout.write(svg(kn.load(sys.argv[1], validate=False)))")
    texts = {subprocess.run([sys.executable, "-c", code, str(ROOT / "models" / "fourbar.json")],
                            capture_output=True, text=True, check=True,
                            env={**os.environ, "PYTHONHASHSEED": seed_}).stdout
             for seed_ in ("1", "2")}
    assert len(texts) == 1


def test_a_half_built_model_draws():
    model = kn.Model("draft")
    model.add(kn.multibody.Ground("ground"))
    model.add(kn.multibody.Revolute("joint"))
    model.add(kn.multibody.RigidBody("body", mass=1.0))
    model.add(kn.rotational.Damper("damper", d=0.1))
    model.add(kn.signals.Gain("gain", k=2.0))
    model.add(kn.Probe("probe"))
    model.connect("ground.frame", "joint.frame_a")          # frame_b, body, damper left open
    root = ET.fromstring(svg(model))
    rects = blocks(root)
    assert set(rects) == set(model.components)
    assert len(wires(root)) == 1
    assert not any(overlap(a, b) for i, a in enumerate(rects.values())
                   for b in list(rects.values())[i + 1:])
    assert ET.fromstring(svg(kn.Model("empty"))).tag == f"{NS}svg"


def test_subsystems_are_blocks_with_their_exposed_ports_and_definition():
    _, _, root = drawn(ROOT / "models" / "engine_v6" / "EngineV6.json")
    cylinders = [g for g in root.iter(f"{NS}g") if g.get("data-type") == "Cylinder"]
    assert sorted(g.get("data-name") for g in cylinders) == [f"cyl{i}" for i in range(1, 7)]
    assert {"cyl3.crank_a", "cyl3.crank_b", "cyl3.cylinder_a", "cyl3.cylinder_b"} <= \
        set(markers(root))


def test_domains_are_coloured_as_in_modelica():
    _, _, root = drawn(ROOT / "models" / "arm_pid.json")
    colour = {(w.get("data-from"), w.get("data-to")): w.get("stroke")
              for w in root.iter(f"{NS}path") if w.get("class") == "wire"}
    assert colour[("ground.frame", "shoulder.frame_a")] == "#5f5f5f"
    assert colour[("spring.flange_b", "shoulder.axis")] == "#404040"
    assert colour[("pid_shoulder.y", "motor_shoulder.u")] == "#00007f"
    shapes = {g.get("data-port"): g[0] for g in root.iter(f"{NS}g") if g.get("class") == "port"}
    assert shapes["shoulder.axis"].get("fill") == "#ffffff"                  # white flange
    assert shapes["pid_shoulder.u_s"].get("fill") == "#00007f"                # filled input
    assert shapes["pid_shoulder.y"].get("fill") == "#ffffff"                  # hollow output
    _, _, spring = drawn(ROOT / "models" / "prismatic_spring.json")
    assert "#007f00" in {w.get("stroke") for w in spring.iter(f"{NS}path")}


def test_jupyter_shows_a_model_as_its_diagram():
    model = seed()
    text = model._repr_svg_()
    assert text == svg(model)
    assert len(blocks(ET.fromstring(text))) == len(model.components)
    # installed by ``import kinetwork`` alone
    subprocess.run([sys.executable, "-c", "import kinetwork, sys; "
                    "sys.exit(not kinetwork.Model('m')._repr_svg_().startswith('<svg'))"],
                   check=True)


def test_the_cli_writes_the_diagram(tmp_path, capsys):
    out = tmp_path / "figures" / "fourbar.svg"
    assert main(["diagram", str(ROOT / "models" / "fourbar.json"), "-o", str(out)]) == 0
    assert "fourbar" in capsys.readouterr().out
    assert len(blocks(ET.fromstring(out.read_text()))) == 16
    assert [p.name for p in out.parent.iterdir()] == ["fourbar.svg"]      # no temporary left


@pytest.mark.parametrize("bad, message", [
    ("folder.svg/", "it is a folder"),
    ("diagram.png", "name a .svg file"),
    ("plain/inside.svg", "cannot write"),
])
def test_the_cli_refuses_a_bad_output_path(tmp_path, capsys, bad, message):
    (tmp_path / "folder.svg").mkdir()
    (tmp_path / "plain").write_text("a file, not a folder")
    target = str(tmp_path / bad.rstrip("/"))
    assert main(["diagram", str(ROOT / "models" / "double_pendulum.json"), "-o", target]) == 1
    err = capsys.readouterr().err
    assert "kinetwork: error:" in err and message in err
    assert not (tmp_path / "diagram.png").exists()


def test_the_cli_draws_a_model_that_does_not_validate(tmp_path):
    text = (ROOT / "models" / "double_pendulum.json").read_text()
    broken = tmp_path / "broken.json"
    # a probe wired to nothing: the model does not validate, the diagram still draws
    broken.write_text(text.replace('["probe1.port", "shoulder.axis"],', ""))
    with pytest.raises(kn.ModelError, match="probe1"):
        kn.load(broken)
    assert main(["diagram", str(broken), "-o", str(tmp_path / "broken.svg")]) == 0
    assert len(wires(ET.fromstring((tmp_path / "broken.svg").read_text()))) == 8


def turned_seed(**turns):
    """The seed with the layout entries of some blocks given a rotation and/or a flip."""
    import json
    data = json.loads((ROOT / "models" / "double_pendulum.json").read_text())
    for name, extra in turns.items():
        data["layout"][name] = {**data["layout"][name], **extra}
    return kn.loads(json.dumps(data), validate=False)


@pytest.mark.parametrize("turn, frame_a, frame_b", [
    ({"rotation": 90}, "top", "bottom"),
    ({"rotation": 180}, "right", "left"),
    ({"rotation": 270}, "bottom", "top"),
    ({"flip": True}, "right", "left"),
    ({"flip": True, "rotation": 90}, "bottom", "top"),
])
def test_rotation_and_flip_in_the_layout_move_the_ports(turn, frame_a, frame_b):
    """A block turned (clockwise, in quarters) or mirrored in the layout has its ports on the
    sides that gives, in the SVG as in the studio: frame_a's marker on the block's edge of
    that side, and the wires still end on their markers."""
    model = turned_seed(link1=turn)
    root = ET.fromstring(svg(model))
    x, y, w, h = blocks(root)["link1"]
    at = markers(root)
    edge = {"left": lambda p: p[0] == pytest.approx(x), "right": lambda p: p[0] == pytest.approx(x + w),
            "top": lambda p: p[1] == pytest.approx(y), "bottom": lambda p: p[1] == pytest.approx(y + h)}
    assert edge[frame_a](at["link1.frame_a"]), at["link1.frame_a"]
    assert edge[frame_b](at["link1.frame_b"]), at["link1.frame_b"]
    for a, b, points in wires(root):
        assert points[0] == pytest.approx(at[a], abs=0.06)
        assert points[-1] == pytest.approx(at[b], abs=0.06)


def test_a_flipped_block_mirrors_its_sign_and_never_its_text():
    """Flip mirrors the glyph (a transform on it alone); names and labels are never mirrored."""
    root = ET.fromstring(svg(turned_seed(shoulder={"flip": True})))
    block = next(g for g in root.iter(f"{NS}g") if g.get("data-name") == "shoulder")
    mirrored = [g for g in block.iter(f"{NS}g") if "scale(-1,1)" in (g.get("transform") or "")]
    assert len(mirrored) == 1 and mirrored[0].find(f"{NS}path").get("class") == "glyph"
    assert not list(mirrored[0].iter(f"{NS}text"))
    assert all("scale" not in (t.get("transform") or "") for t in root.iter(f"{NS}text"))
    # the names still read "shoulder", left to right
    assert "shoulder" in [t.text for t in block.iter(f"{NS}text")]
