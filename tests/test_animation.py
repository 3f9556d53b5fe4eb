"""3-D animation: the poses are the frame probes', the scene draws every part, the page is
self-contained and plays in a browser, the command writes HTML and GIF, bad paths are refused."""

import io
import json
import os
import re

import numpy as np
import pytest
from scenes import double_pendulum, spring_pendulum

import kinetwork as kn
from kinetwork import animation
from kinetwork.animation import animation_data, video
from kinetwork.cli import main

MODELS = os.path.join(os.path.dirname(__file__), os.pardir, "models")


def probed(model):
    """``model`` with a position and orientation probe on every frame port (but probes')."""
    ports = [f"{c.name}.{p}" for c in list(model.components.values()) if c.role != "probe"
             for p, port in c.ports.items() if port.domain == "frame"]
    for k, path in enumerate(ports):
        model.add(kn.Probe(f"pose{k}", quantities=["position", "orientation"]))
        model.connect(f"pose{k}.port", path)
    return model, {path: f"pose{k}" for k, path in enumerate(ports)}


def rotation(q):
    """The rotation matrix of a unit quaternion [w, x, y, z] (independent of the code)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def scene(name):
    if name == "double_pendulum":
        return double_pendulum(q0=(1.0, -0.5))
    return kn.load(os.path.join(MODELS, f"{name}.json"))


@pytest.fixture(scope="module")
def seed_run():
    m = double_pendulum(q0=(1.0, -0.5))
    return m, kn.simulate(m, t_end=2.0, n_points=201)


@pytest.mark.parametrize("name", ["double_pendulum", "spatial_arm", "fourbar", "slider_crank",
                                  "spatial_fourbar"])
def test_poses_are_the_frame_probes(name):
    """Every frame of the scene sits where a frame probe on its ports says, to 1e-9; each
    centre of mass at r + R r_cm of its body's frame_a."""
    m, probe_of = probed(scene(name))
    res = kn.simulate(m, t_end=1.0, n_points=51)
    anim = animation_data(res, model=m)
    assert len(anim["t"]) == 51
    np.testing.assert_array_equal(anim["t"], res.t)
    by_name = {f["name"]: f for f in anim["frames"]}
    checked = 0
    for frame in anim["frames"]:
        pos, quat = np.array(frame["position"]), np.array(frame["quaternion"])
        assert pos.shape[1:] == (3,) and quat.shape[1:] == (4,) and len(pos) in (1, 51)
        np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-12)
        R = np.array([rotation(q) for q in quat])
        for port in frame["ports"]:
            probe = probe_of[port]
            np.testing.assert_allclose(np.broadcast_to(pos, (51, 3)), res[f"{probe}.position"],
                                       rtol=0, atol=1e-9, err_msg=port)
            np.testing.assert_allclose(np.broadcast_to(R, (51, 3, 3)),
                                       res[f"{probe}.orientation"], rtol=0, atol=1e-9,
                                       err_msg=port)
            checked += 1
    assert checked == len(probe_of)          # every frame port of the model is in the scene
    values = m.numeric_values()
    for body in (c for c in m.components.values() if c.type_name == "multibody.RigidBody"):
        probe = probe_of[f"{body.name}.frame_a"]
        r_cm = values[body.name]["r_cm"]
        expected = res[f"{probe}.position"] + res[f"{probe}.orientation"] @ r_cm
        np.testing.assert_allclose(by_name[f"{body.name}.cm"]["position"], expected, rtol=0,
                                   atol=1e-9)


def test_a_loop_stays_closed_in_the_animation():
    """The cut joint's two frames coincide at every time: the animated four-bar never
    comes apart."""
    m = kn.load(os.path.join(MODELS, "fourbar.json"))
    res = kn.simulate(m, t_end=2.0, n_points=101)
    frames = {p: f for f in animation_data(res, model=m)["frames"] for p in f["ports"]}
    a, b = (np.array(frames[f"C.{p}"]["position"]) for p in ("frame_a", "frame_b"))
    assert np.ptp(a[:, 0]) > 0.1                           # it moves
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)


def test_the_animation_is_json_and_says_what_it_holds(seed_run):
    m, res = seed_run
    anim = animation_data(res, model=m)
    again = json.loads(json.dumps(anim, allow_nan=False))
    assert again == anim
    assert (anim["format"], anim["version"], anim["name"]) == ("kinetwork.animation", 1,
                                                               "double_pendulum")
    assert [f["name"] for f in anim["frames"]] == [
        "ground.frame", "shoulder.frame_b", "elbow.frame_a", "elbow.frame_b", "mass1.cm",
        "mass2.cm"]
    assert anim["frames"][0]["ports"] == ["ground.frame", "shoulder.frame_a"]
    assert len(anim["frames"][0]["position"]) == 1          # the ground never moves
    assert all(len(f["position"]) == 201 for f in anim["frames"][1:])
    n = len(anim["frames"])
    for shape in anim["shapes"]:
        assert 0 <= shape["frame"] < n and 0 <= shape.get("to", 0) < n
        assert re.fullmatch("#[0-9a-f]{6}", shape["color"])
    lo, hi = np.array(anim["bounds"])
    assert anim["scale"] == pytest.approx(np.max(hi - lo))
    assert anim["view"]["up"] == [0.0, 1.0, 0.0]            # against gravity (-y)
    assert abs(anim["view"]["direction"][2]) > 0.8           # faces the plane of motion


def test_resampled_to_frames_per_second(seed_run):
    m, res = seed_run
    anim = animation_data(res, fps=25, model=m)
    np.testing.assert_allclose(anim["t"], np.arange(51) / 25, atol=1e-12)
    exact = animation_data(res, model=m)
    k = 3                                      # elbow.frame_b: t = 0.4 s is a grid point
    np.testing.assert_allclose(anim["frames"][k]["position"][10],
                               exact["frames"][k]["position"][40], atol=1e-12)
    quat = np.array(anim["frames"][k]["quaternion"])
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-12)
    with pytest.raises(kn.ModelError, match="fps"):
        animation_data(res, fps=0, model=m)




def test_poses_rounded_for_a_player(seed_run):
    """With a resolution, every position is within half of its power of ten times the scale
    of the exact pose and every quaternion within half of it; the JSON is far shorter."""
    m, res = seed_run
    exact = animation_data(res, model=m)
    rounded = animation_data(res, model=m, resolution=1e-7)
    step = 10.0 ** np.floor(np.log10(1e-7 * exact["scale"]))     # 1e-7 m for the 2 m seed
    assert step <= 1e-7 * exact["scale"]
    for a, b in zip(exact["frames"], rounded["frames"]):
        for key, tol in (("position", step), ("quaternion", 1e-7)):
            diff = np.abs(np.array(a[key]) - np.array(b[key]))
            assert diff.max() <= tol / 2 * (1 + 1e-9), (a["name"], key, diff.max())
    assert {k: v for k, v in rounded.items() if k != "frames"} == \
        {k: v for k, v in exact.items() if k != "frames"}
    assert len(json.dumps(rounded)) < 0.7 * len(json.dumps(exact))
def shapes_of(anim, component):
    return [s for s in anim["shapes"] if s["component"] == component]


def test_default_visuals_of_the_seed(seed_run):
    m, res = seed_run
    anim = animation_data(res, model=m)
    L = anim["scale"]
    [shoulder] = shapes_of(anim, "shoulder")
    assert shoulder["kind"] == "cylinder" and shoulder["length_direction"] == [0.0, 0.0, 1.0]
    assert shoulder["length"] == pytest.approx(L / 10)
    np.testing.assert_allclose(shoulder["r_shape"], [0, 0, -L / 20])     # centred on the axis
    [link] = shapes_of(anim, "link1")
    assert (link["kind"], link["frame"], link["to"]) == ("rod", 1, 2)
    # mass1 sits half-way along link1: its own rod would only hide in the link's
    assert [s["kind"] for s in shapes_of(anim, "mass1")] == ["sphere"]
    assert [s["kind"] for s in shapes_of(anim, "mass2")] == ["sphere", "rod"]
    sphere = shapes_of(anim, "mass2")[0]
    assert sphere["frame"] == 5 and sphere["length"] == pytest.approx(L / 9)
    ground = shapes_of(anim, None)
    assert {s["kind"] for s in ground} == {"grid", "axes"}
    assert sum(s["kind"] == "axes" for s in ground) == 4     # the ground's and 3 moving frames'


@pytest.mark.parametrize("name, component, kinds", [
    ("spatial_arm", "extend", ["box", "box"]),         # prismatic: rail and slider
    ("spatial_arm", "tilt", []),                       # a rotation in place: nothing to draw
    ("spatial_fourbar", "U", ["sphere"]),
    ("spatial_fourbar", "S", ["sphere"]),
    ("slider_crank", "rod", ["rod"]),
])
def test_default_visuals(name, component, kinds):
    m = scene(name)
    anim = animation_data(kn.simulate(m, t_end=0.5, n_points=11), model=m)
    assert [s["kind"] for s in shapes_of(anim, component)] == kinds


def test_prismatic_rail_covers_the_travel():
    m = scene("slider_crank")
    res = kn.simulate(m, t_end=1.0, n_points=51)
    rail, slider = shapes_of(animation_data(res, model=m), "slider")
    q = res["slider.q"]
    assert rail["r_shape"][0] == pytest.approx(min(q.min(), 0))
    assert rail["length"] == pytest.approx(max(q.max(), 0) - min(q.min(), 0), abs=1e-6)
    assert slider["frame"] != rail["frame"]


def test_line_forces_are_coils():
    m = spring_pendulum()
    anim = animation_data(kn.simulate(m, t_end=0.5, n_points=11), model=m)
    forces = [s for s in anim["shapes"] if s["kind"] == "spring"]
    assert forces and all(s["frame"] != s["to"] for s in forces)


def test_shaped_bodies_are_drawn_as_modelica_draws_them():
    m = kn.Model("shaped")
    m.add(kn.multibody.Ground("ground"))
    m.add(kn.multibody.Revolute("j", axis=[0, 0, 1], q0=0.3))
    m.add(kn.multibody.BodyBox("box", r=[1, 0, 0], width=0.1, height=0.05, density=7700.0))
    m.add(kn.multibody.BodyCylinder("cyl", r=[0, -0.5, 0], diameter=0.05, density=7700.0))
    m.add(kn.multibody.BodySphere("ball", diameter=0.2, density=7700.0))
    for a, b in [("ground.frame", "j.frame_a"), ("j.frame_b", "box.frame_a"),
                 ("box.frame_b", "cyl.frame_a"), ("cyl.frame_b", "ball.frame_a")]:
        m.connect(a, b)
    anim = animation_data(kn.simulate(m, t_end=0.2, n_points=5), model=m)
    [box] = shapes_of(anim, "box")
    assert box["kind"] == "box" and box["length_direction"] == [1.0, 0.0, 0.0]
    assert (box["length"], box["width"], box["height"]) == pytest.approx((1.0, 0.1, 0.05))
    [cyl] = shapes_of(anim, "cyl")
    assert cyl["kind"] == "cylinder" and cyl["length_direction"] == [0.0, -1.0, 0.0]
    assert (cyl["length"], cyl["width"]) == pytest.approx((0.5, 0.05))
    [ball] = shapes_of(anim, "ball")
    assert ball["kind"] == "sphere" and ball["length"] == pytest.approx(0.2)
    np.testing.assert_allclose(np.add(ball["r_shape"], 0.1 * np.array(ball["length_direction"])),
                               0, atol=1e-12)            # centred on frame_a


def test_a_rigid_body_with_a_shape():
    m = double_pendulum()
    m.components["mass1"].set_param("shape", "box")
    m.components["mass1"].set_param("shape_size", [0.4, 0.2, 0.1])
    anim = animation_data(kn.simulate(m, t_end=0.2, n_points=5), model=m)
    [box] = shapes_of(anim, "mass1")
    assert box["kind"] == "box" and box["frame"] == 1
    assert (box["length"], box["width"], box["height"]) == pytest.approx((0.4, 0.2, 0.1))
    np.testing.assert_allclose(box["r_shape"], [-0.2, -0.5, 0], atol=1e-12)   # about the CM


def test_results_that_do_not_say_their_model(seed_run):
    m, res = seed_run
    if res.system is not None:
        assert res.system.model is m
        return
    with pytest.raises(kn.ModelError, match="model="):
        animation_data(res)
    with pytest.raises(kn.ModelError, match="not of model 'fourbar'"):
        animation_data(res, model=scene("fourbar"))


# -- the page -----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def seed_page(seed_run, tmp_path_factory):
    m, res = seed_run
    path = tmp_path_factory.mktemp("page") / "seed.html"
    anim = res.animate(path, model=m)
    return path, anim


def test_the_page_is_self_contained(seed_page):
    path, anim = seed_page
    text = path.read_text(encoding="utf-8")
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:)?//""", text, re.I)
    assert not re.search(r"<(link|iframe|img|object|embed)\b", text, re.I)
    assert len(re.findall(r"<script\b", text)) == 2
    assert "default-src 'none'" in text                      # nothing may be fetched
    data = re.search(r'<script type="application/json" id="kinetwork-animation">(.*?)</script>',
                     text, re.S).group(1)
    embedded = json.loads(data)
    assert embedded["shapes"] == anim["shapes"]
    np.testing.assert_allclose(embedded["t"], anim["t"], rtol=0, atol=1e-9)
    scale = anim["scale"]
    for mine, theirs in zip(anim["frames"], embedded["frames"]):
        np.testing.assert_allclose(theirs["position"], mine["position"], atol=1e-6 * scale)
    assert len(text) < 2_000_000


def test_a_model_name_cannot_break_the_page(seed_run, tmp_path):
    m, res = seed_run
    anim = animation_data(res, model=m)
    anim["name"] = "</script><script>alert(1)</script>"
    page = animation.html_page(anim)
    assert page.count("</script>") == 2 and "alert(1)</script>" not in page


def picture(png):
    from PIL import Image
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def test_the_page_plays_in_chromium(seed_page, chromium):
    path, anim = seed_page
    context = chromium.new_context(viewport={"width": 800, "height": 600})
    try:
        page = context.new_page()
        problems, requests = [], []
        page.on("console", lambda msg: msg.type == "error" and problems.append(msg.text))
        page.on("pageerror", lambda exc: problems.append(str(exc)))
        page.on("request", lambda req: requests.append(req.url))
        page.goto(path.as_uri())
        # a function, not an expression: Playwright polls an expression with eval, which the
        # page's Content-Security-Policy refuses (the test failed whenever it had to poll)
        page.wait_for_function("() => window.kinetworkPlayer && "
                               "window.kinetworkPlayer.getTime() > 0.2")
        assert page.evaluate("window.kinetworkPlayer.isPlaying()")
        page.evaluate("window.kinetworkPlayer.pause(); window.kinetworkPlayer.setTime(0)")
        page.wait_for_timeout(200)
        canvas = page.locator("canvas")
        first = picture(canvas.screenshot())
        page.evaluate("window.kinetworkPlayer.setTime(0.9)")
        page.wait_for_timeout(200)
        later = picture(canvas.screenshot())
        assert page.evaluate("window.kinetworkPlayer.getTime()") == 0.9
        page.evaluate("window.kinetworkPlayer.play()")
        page.locator(".kn-play").click()                                  # the pause button
        stopped = page.evaluate("window.kinetworkPlayer.getTime()")
        page.wait_for_timeout(200)
        assert page.evaluate("window.kinetworkPlayer.getTime()") == stopped
        page.mouse.move(400, 300)
        page.mouse.down()
        page.mouse.move(480, 320, steps=5)                             # orbit the camera
        page.mouse.up()
        page.wait_for_timeout(200)
        orbited = picture(canvas.screenshot())
        seen = page.evaluate("""async () => {      // a second viewer, as the studio makes one
            const box = document.createElement("div");
            box.style.cssText = "position:fixed;left:0;top:0;width:200px;height:150px";
            document.body.appendChild(box);
            const data = JSON.parse(document.getElementById("kinetwork-animation").textContent);
            const seen = [];
            const viewer = KinetworkPlayer.createViewer(
                box, data, {onTime: t => seen.push([t, performance.now() / 1000])});
            viewer.setSpeed(0.5);
            viewer.play();
            const start = performance.now();
            // measured from 0.5 s after play on, over 1.5 s: the first frames are slow
            // (shaders, first drawing), and a time given to onTime is its frame's, earlier
            // than the clock read in the callback by that frame's delay (once 0.4 s more at
            // the start than at the end, on a loaded machine)
            const from = () => seen.findIndex(s => s[1] - seen[0][1] >= 0.5);
            const enough = () => from() >= 0 && seen.at(-1)[1] - seen[from()][1] > 1.5;
            while (!enough() && performance.now() - start < 20000)
                await new Promise(r => setTimeout(r, 50));
            viewer.dispose();
            return [seen.slice(from()), box.querySelectorAll("canvas").length];
        }""")
    finally:
        context.close()
    assert not problems, problems
    assert requests == [path.as_uri()]
    seen, canvases = seen
    assert canvases == 0                                                 # disposed
    (t0, w0), (t1, w1) = seen[0], seen[-1]                # onTime while playing, at 0.5x
    assert 0.4 < ((t1 - t0) % 2.0) / (w1 - w0) < 0.6      # (the 2 s run loops)
    background = np.array([244, 245, 247])
    drawn = np.any(np.abs(first - background) > 30, axis=2)
    assert drawn.mean() > 0.01                                   # not a blank canvas
    blue = (first[..., 2] > 200) & (first[..., 0] < 80)           # the bodies
    assert blue.sum() > 200
    assert np.abs(later - first).sum(axis=2).astype(bool).mean() > 0.002   # it moved
    assert np.abs(orbited - later).sum(axis=2).astype(bool).mean() > 0.01  # the view turned


# -- videos and the command -----------------------------------------------------------------------
def test_gif(seed_run, tmp_path):
    from PIL import Image
    m, res = seed_run
    anim = res.animate(gif=tmp_path / "seed.gif", fps=10, model=m, height=200)
    with Image.open(tmp_path / "seed.gif") as im:
        assert im.n_frames == len(anim["t"]) == 21
        assert im.size[1] == 200 and im.info["duration"] == 100 and im.info["loop"] == 0
        im.seek(0)
        first = np.asarray(im.convert("RGB")).astype(int)
        im.seek(9)
        later = np.asarray(im.convert("RGB")).astype(int)
    assert np.any(np.abs(first - [244, 245, 247]) > 30, axis=2).mean() > 0.01
    assert np.any(first != later)


def test_mp4_needs_ffmpeg(seed_run, tmp_path, monkeypatch):
    m, res = seed_run
    monkeypatch.setattr(video, "find_ffmpeg", lambda: None)
    with pytest.raises(kn.ModelError, match="imageio-ffmpeg"):
        res.animate(mp4=tmp_path / "seed.mp4", model=m)
    assert not (tmp_path / "seed.mp4").exists()


def test_mp4(seed_run, tmp_path):
    m, res = seed_run
    res.animate(mp4=tmp_path / "seed.mp4", fps=10, model=m, height=120)
    head = (tmp_path / "seed.mp4").read_bytes()[:12]
    assert head[4:8] == b"ftyp"


def test_command_writes_html_and_gif(seed_file, tmp_path, capsys):
    html, gif = tmp_path / "out" / "seed.html", tmp_path / "out" / "seed.gif"
    assert main(["animate", str(seed_file), "--html", str(html), "--gif", str(gif),
                 "--t-end", "1", "--fps", "10"]) == 0
    out = capsys.readouterr().out
    assert f"wrote html {html}" in out and f"wrote gif {gif}" in out
    text = html.read_text(encoding="utf-8")
    anim = json.loads(re.search(r'id="kinetwork-animation">(.*?)</script>', text, re.S).group(1))
    assert len(anim["t"]) == 11
    assert gif.read_bytes()[:6] == b"GIF89a"


def test_command_animates_a_loop(tmp_path):
    gif = tmp_path / "fourbar.gif"
    assert main(["animate", os.path.join(MODELS, "slider_crank.json"), "--gif", str(gif),
                 "--t-end", "0.5", "--fps", "8"]) == 0
    assert gif.stat().st_size > 1000


@pytest.mark.parametrize("args, message, code", [
    ([], "nothing to write", 1),
    (["--html", "{tmp}/x.gif"], "must be a .html file", 1),
    (["--gif", "{tmp}/x.html"], "must be a .gif file", 1),
    (["--gif", "{tmp}"], "is a folder", 1),
    (["--html", "{model}"], "is an input here (the model file", 2),
    (["--html", "{tmp}/file.txt/x.html"], "cannot write", 1),
])
def test_command_refuses_bad_paths(seed_file, tmp_path, capsys, args, message, code):
    (tmp_path / "file.txt").write_text("not a folder")
    before = seed_file.read_bytes()
    args = [a.format(tmp=tmp_path, model=seed_file) for a in args]
    assert main(["animate", str(seed_file), *args, "--t-end", "0.1"]) == code
    assert message in capsys.readouterr().err
    assert seed_file.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == sorted(["file.txt", seed_file.name])


@pytest.mark.parametrize("kwargs, message", [
    ({}, "nothing to write"),
    ({"path": "{tmp}/missing/x.html"}, "cannot write"),
    ({"path": "{tmp}/x.txt"}, "must be a .html file"),
    ({"gif": "{tmp}"}, "is a folder"),
])
def test_animate_refuses_bad_paths(seed_run, tmp_path, kwargs, message):
    m, res = seed_run
    kwargs = {k: v.format(tmp=tmp_path) for k, v in kwargs.items()}
    with pytest.raises(kn.ModelError, match=message):
        res.animate(model=m, **kwargs)
    assert os.listdir(tmp_path) == []


def test_a_loop_rod_is_drawn_as_a_rod_of_its_length():
    """MSL's Fourbar2 closes through a UniversalSpherical: a ball at either end and a rod
    between, whose end frames stay the rod's length |r_rod| apart in every pose (the loop's
    closure, read from the animation's own poses)."""
    model = kn.load(os.path.join(MODELS, "fourbar2.json"))
    res = kn.simulate(model, t_end=0.5, n_points=21)
    anim = animation_data(res)
    rods = [s for s in anim["shapes"] if s["kind"] == "rod"]
    frames = anim["frames"]
    joint = model.components["universalSpherical"]
    a = next(i for i, f in enumerate(frames) if "universalSpherical.frame_a" in f["ports"])
    b = next(i for i, f in enumerate(frames) if "universalSpherical.frame_b" in f["ports"])
    assert any(r["frame"] == a and r["to"] == b for r in rods)
    spheres = {s["frame"] for s in anim["shapes"] if s["kind"] == "sphere"}
    assert {a, b} <= spheres
    pa, pb = (np.asarray(frames[i]["position"], dtype=float) for i in (a, b))
    length = np.linalg.norm(joint.r_rod)
    np.testing.assert_allclose(np.linalg.norm(pb - pa, axis=1), length, rtol=0, atol=1e-9)
