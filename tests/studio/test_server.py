"""The studio's server against its contract (kinetwork/studio/API.md): the token, the palette,
files confined to the root, the checks of kn.load placed on their blocks, saves that keep
files byte for byte, and runs that end as kn.simulate ends (done, failed, cancelled)."""

import json
import os
import pathlib
import sys
import time
import types
import warnings

import httpx
import numpy as np
import pytest
import uvicorn
with warnings.catch_warnings():
    # starlette asks for httpx2 now and says so on import; httpx still does the job
    warnings.filterwarnings("ignore", message="Using `httpx` with `starlette.testclient`")
    from fastapi.testclient import TestClient

import kinetwork as kn
from kinetwork.components.base import REGISTRY
from kinetwork.studio import launch, results, runs
from kinetwork.studio.checks import plain
from kinetwork.studio.server import TOKEN_HEADER, create_app
from tests.studio.helpers import serving

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
MODEL_FILES = sorted(p.relative_to(MODELS).as_posix() for p in MODELS.rglob("*.json"))
TOKEN = "test-token-0123456789"
SEED = "models/double_pendulum.json"


@pytest.fixture
def client(root):
    with TestClient(create_app(root, TOKEN), headers={TOKEN_HEADER: TOKEN}) as c:
        yield c


def seed(client):
    return client.get("/api/open", params={"path": SEED}).json()["model"]


def with_params(data, component, **params):
    data = json.loads(json.dumps(data))
    next(c for c in data["components"] if c["name"] == component)["params"].update(params)
    return data


def wait(client, run_id, timeout=120.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        answer = client.get(f"/api/run/{run_id}").json()
        if answer["state"] != "running":
            return answer
        time.sleep(0.05)
    raise AssertionError(f"run {run_id} still going after {timeout} s")


# -- the token ---------------------------------------------------------------------------------
API_GETS = ["/api/palette", "/api/schema", "/api/files", "/api/examples",
            f"/api/open?path={SEED}", "/api/run/r1", "/api/run/r1/animation"]
API_POSTS = ["/api/validate", "/api/save", "/api/run", "/api/run/r1/cancel"]


@pytest.mark.parametrize("route", API_GETS + API_POSTS)
@pytest.mark.parametrize("headers", [{}, {TOKEN_HEADER: "wrong"}, {TOKEN_HEADER: ""},
                                     {TOKEN_HEADER: TOKEN + "x"}])
def test_api_refuses_a_missing_or_wrong_token(root, route, headers):
    c = TestClient(create_app(root, TOKEN))
    answer = c.get(route, headers=headers) if route in API_GETS else \
        c.post(route, headers=headers, json={})
    assert answer.status_code == 403
    assert "token" in answer.json()["error"]


def test_token_in_the_query_or_the_header(root):
    c = TestClient(create_app(root, TOKEN))
    assert c.get("/api/examples", params={"token": TOKEN}).status_code == 200
    assert c.get("/api/examples", headers={TOKEN_HEADER: TOKEN}).status_code == 200
    assert c.get("/api/examples", params={"token": "nope"}).status_code == 403


def test_the_page_needs_the_token_and_assets_do_not(root):
    c = TestClient(create_app(root, TOKEN))
    assert c.get("/").status_code == 403
    page = c.get("/", params={"token": TOKEN})
    assert page.status_code == 200 and "<html" in page.text.lower()
    # no token asked of assets: a missing one is a 404, never a 403
    assert c.get("/assets/missing.js").status_code == 404
    assert c.get("/assets/../server.py").status_code == 404
    # a NUL or an endless name is no asset, never a 500
    assert c.get("/assets/%00").status_code == 404
    assert c.get("/assets/a%00.js").status_code == 404
    assert c.get("/assets/" + "a" * 5000 + ".js").status_code == 404


# -- palette, schema, files, examples ------------------------------------------------------------
def test_palette_lists_every_registry_type_with_its_params_and_units(client):
    libraries = client.get("/api/palette").json()["libraries"]
    found = {t["type"]: (lib["name"], t) for lib in libraries for t in lib["types"]}
    assert set(found) == set(REGISTRY)
    for type_name, cls in REGISTRY.items():
        library, info = found[type_name]
        assert library == (type_name.split(".")[0] if "." in type_name else "probe")
        assert [p["name"] for p in info["params"]] == list(cls.params)
        assert [p["unit"] for p in info["params"]] == [s.unit for s in cls.params.values()]
        assert [p["required"] for p in info["params"]] == \
            [s.required for s in cls.params.values()]
        assert [(p["name"], p["domain"]) for p in info["ports"]] == \
            [(name, port.domain) for name, port in cls.ports.items()]
    mass = next(p for p in found["multibody.RigidBody"][1]["params"] if p["name"] == "mass")
    assert mass["unit"] == "kg" and mass["min"] == 0


def test_schema_is_kn_schema(client):
    assert client.get("/api/schema").json() == json.loads(json.dumps(kn.schema()))


def test_files_lists_the_models_under_the_root(client, root):
    (root / "deep" / "a" / "b" / "c" / "d").mkdir(parents=True)
    (root / "deep" / "a" / "b" / "c" / "d" / "too_deep.json").write_text("{}")
    (root / "deep" / "a" / "b" / "c" / "ok.json").write_text("{}")
    (root / ".hidden").mkdir()
    (root / ".hidden" / "x.json").write_text("{}")
    answer = client.get("/api/files").json()
    assert answer["root"] == os.path.realpath(root)
    assert {f"models/{f}" for f in MODEL_FILES} <= set(answer["files"])
    assert "deep/a/b/c/ok.json" in answer["files"]
    assert "deep/a/b/c/d/too_deep.json" not in answer["files"]
    assert not any(".hidden" in f for f in answer["files"])


def test_examples_come_from_the_models_folder(client):
    names = client.get("/api/examples").json()["examples"]
    assert "double_pendulum" in names and "engine_v6/EngineV6" in names
    assert "engine_v6/Cylinder" not in names        # a definition, part of an example
    opened = client.get("/api/open", params={"example": "double_pendulum"}).json()
    assert opened["path"] is None
    assert opened["text"] == (MODELS / "double_pendulum.json").read_text()
    assert client.get("/api/open", params={"example": "nope"}).status_code == 404


def test_an_example_of_subsystem_files_opens_self_contained(client):
    """Its definitions come inline (their files stay in the examples' folder), so it
    validates, runs and saves anywhere."""
    opened = client.get("/api/open", params={"example": "engine_v6/EngineV6"}).json()
    assert "file" not in json.dumps(opened["model"]["definitions"])
    answer = client.post("/api/validate", json={"model": opened["model"]}).json()
    assert answer["ok"] and answer["summary"]["dof"] == 1


# -- open and save -------------------------------------------------------------------------------
@pytest.mark.parametrize("verbatim", [True, False], ids=["text", "model"])
@pytest.mark.parametrize("name", MODEL_FILES)
def test_open_then_save_unchanged_is_byte_identical(client, root, name, verbatim):
    path = f"models/{name}"
    before = (root / path).read_bytes()
    opened = client.get("/api/open", params={"path": path}).json()
    assert opened["path"] == path and opened["text"] == before.decode()
    model = json.loads(json.dumps(opened["model"]))       # as the page holds it
    answer = client.post("/api/save", json={"path": path, "model": model,
                                            "text": opened["text"] if verbatim else None,
                                            "base": opened["version"]})
    assert answer.status_code == 200, answer.json()
    assert answer.json() == {"ok": True, "bytes": len(before), "text": before.decode(),
                             "version": opened["version"], "problems": []}
    assert (root / path).read_bytes() == before


def test_save_of_a_changed_model_writes_kinetworks_text(client, root):
    opened = client.get("/api/open", params={"path": SEED}).json()
    changed = with_params(opened["model"], "mass1", mass=2.5)
    changed["layout"] = {"mass1": {"x": 10, "y": 20}}
    answer = client.post("/api/save", json={"path": "models/new.json", "model": changed,
                                            "text": opened["text"]}).json()
    model = kn.load(root / "models" / "new.json")
    assert model.components["mass1"].given["mass"] == 2.5
    assert model.layout == {"mass1": {"x": 10, "y": 20}}
    assert answer["text"] == kn.dumps(model) == (root / "models" / "new.json").read_text()


def test_save_keeps_a_half_built_model(client, root):
    """Work in progress (a body wired to nothing) saves: kn.load(validate=False) reads it."""
    data = seed(client)
    data["connections"] = []
    assert client.post("/api/save", json={"path": "wip.json", "model": data}).status_code == 200
    assert kn.load(root / "wip.json", validate=False).connections == []


@pytest.mark.parametrize("change, where", [
    (lambda d: d["components"].append({"name": "x", "type": "multibody.Nope"}), "unknown type"),
    (lambda d: d["components"][4]["params"].pop("mass"), "a value is required"),
    (lambda d: d["components"][4]["params"].update(mass="m1 +"), "cannot parse"),
    (lambda d: d.__setitem__("layout", {"nobody": {"x": 0}}), "layout.nobody"),
    (lambda d: d.__setitem__("simulation", {"t_end": -1}), "t_end"),
], ids=["unknown type", "required value empty", "half-typed expression", "layout",
        "settings"])
def test_unfinished_work_saves_as_it_is_and_its_problems_come_back(client, root, change,
                                                                     where):
    """Work in progress that the reader refuses is written as it is (never lost), with its
    problems in the answer; kn.load lists them; opened again it is the same model."""
    data = seed(client)
    change(data)
    answer = client.post("/api/save", json={"path": "models/wip.json", "model": data})
    assert answer.status_code == 200, answer.json()
    assert any(where in p["message"] for p in answer.json()["problems"])
    assert json.loads((root / "models" / "wip.json").read_text()) == data
    assert (root / "models" / "wip.json").read_text() == answer.json()["text"]
    with pytest.raises(kn.ModelError, match=where.split()[0]):
        kn.load(root / "models" / "wip.json")
    opened = client.get("/api/open", params={"path": "models/wip.json"}).json()
    assert opened["model"] == data
    problems = client.post("/api/validate", json={"model": opened["model"]}).json()["problems"]
    assert any(where in p["message"] for p in problems)
    assert not [p for p in (root / "models").iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("model", [{"components": []}, {"format": "other"}],
                         ids=["no format", "another format"])
def test_save_never_writes_what_is_not_a_model_file(client, root, model):
    before = (root / SEED).read_bytes()
    answer = client.post("/api/save", json={"path": SEED, "model": model})
    assert answer.status_code == 400 and "format" in answer.json()["error"]
    assert (root / SEED).read_bytes() == before


def test_save_does_not_overwrite_other_json_files(client, root):
    (root / "package.json").write_text('{"name": "not a model"}')
    answer = client.post("/api/save", json={"path": "package.json", "model": seed(client)})
    assert answer.status_code == 409
    assert (root / "package.json").read_text() == '{"name": "not a model"}'
    answer = client.post("/api/save", json={"path": "models", "model": seed(client)})
    assert answer.status_code == 400
    answer = client.post("/api/save", json={"path": "new/a.json", "model": seed(client)})
    assert answer.status_code == 400 and "does not exist" in answer.json()["error"]


@pytest.fixture
def outside(tmp_path_factory):
    folder = tmp_path_factory.mktemp("outside")
    (folder / "secret.json").write_text('{"format": "kinetwork.model"}')
    return folder


@pytest.mark.parametrize("path", [
    "../x.json", "models/../../x.json", "..\\x.json", "/etc/passwd", "/tmp/x.json",
    "C:/x.json", "file:///etc/x.json", "~/x.json", "", "models", "models/a.txt", "a\x00.json",
    "LINK/secret.json", "link.json",
])
def test_paths_leaving_the_root_are_refused(client, root, outside, path):
    (root / "LINK").symlink_to(outside, target_is_directory=True)
    (root / "link.json").symlink_to(outside / "secret.json")
    data = seed(client)
    for answer in (client.get("/api/open", params={"path": path}),
                   client.post("/api/save", json={"path": path, "model": data}),
                   client.post("/api/validate", json={"model": data, "path": path}),
                   client.post("/api/run", json={"model": data, "path": path})):
        assert answer.status_code == 400, (path, answer.json())
        assert answer.json()["error"]
    assert (outside / "secret.json").read_text() == '{"format": "kinetwork.model"}'
    assert not (root.parent / "x.json").exists()


def test_open_of_a_missing_or_broken_file(client, root):
    assert client.get("/api/open", params={"path": "nope.json"}).status_code == 404
    (root / "broken.json").write_text('{"format": ')
    answer = client.get("/api/open", params={"path": "broken.json"})
    assert answer.status_code == 400 and "invalid JSON" in answer.json()["error"]
    assert client.get("/api/open").status_code == 400


# -- validate ----------------------------------------------------------------------------------
def test_validate_the_seed(client):
    answer = client.post("/api/validate", json={"model": seed(client)}).json()
    assert answer["ok"] and answer["problems"] == []
    assert answer["summary"]["dof"] == 2 and answer["summary"]["components"] == 9
    assert answer["summary"]["states"] == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]


def test_validate_places_a_bad_value_on_its_block(client):
    answer = client.post("/api/validate",
                         json={"model": with_params(seed(client), "mass1", mass=-1)}).json()
    assert not answer["ok"]
    [problem] = answer["problems"]
    assert (problem["component"], problem["param"], problem["connection"]) == \
        ("mass1", "mass", None)
    assert "must be >= 0" in problem["message"]


@pytest.mark.parametrize("pair", [["ground.frame", "spring.flange_a"],
                                  ["ground.frame", "nobody.frame"],
                                  ["ground.frame", "mass1.nope"]],
                         ids=["domains", "component", "port"])
def test_validate_places_a_wrong_wire_on_its_connection(client, pair):
    data = seed(client)
    data["connections"][3] = pair
    problems = client.post("/api/validate", json={"model": data}).json()["problems"]
    assert any(p["connection"] == 3 and p["component"] is None for p in problems), problems


def test_validate_names_the_component_of_a_port_problem(client):
    data = seed(client)
    data["connections"] = [c for c in data["connections"] if "shoulder.frame_a" not in c]
    problems = client.post("/api/validate", json={"model": data}).json()["problems"]
    assert {"shoulder", "mass1"} <= {p["component"] for p in problems}


@pytest.mark.filterwarnings("ignore::kinetwork.IdealisedInertiaWarning")   # sent as data
def test_validate_sends_the_fields_of_each_problem_and_its_warnings(client):
    data = with_params(seed(client), "mass1", mass=-1.0)
    answer = client.post("/api/validate", json={"model": data}).json()
    index = [c["name"] for c in data["components"]].index("mass1")
    problem = next(p for p in answer["problems"] if p["component"] == "mass1")
    assert set(problem) == {"message", "component", "port", "parameter", "path", "hint",
                            "severity", "reason", "param", "connection"}
    assert (problem["parameter"], problem["path"], problem["severity"]) == \
        ("mass", f"components[{index}].params.mass", "error")
    assert problem["param"] == "mass" and answer["warnings"] == []
    # an inertia no rigid body has: accepted, with a warning on the body and its parameter
    data = with_params(seed(client), "mass1", inertia=[1.0, 0.1, 0.1])
    answer = client.post("/api/validate", json={"model": data}).json()
    assert answer["ok"] and answer["problems"] == []
    [warning] = answer["warnings"]
    assert (warning["component"], warning["parameter"], warning["severity"]) == \
        ("mass1", "inertia", "warning")
    assert warning["path"] == f"components[{index}].params.inertia"


def test_validate_finds_subsystem_files_next_to_the_model(client):
    path = "models/robot/arm_axes.json"
    data = client.get("/api/open", params={"path": path}).json()["model"]
    assert client.post("/api/validate", json={"model": data, "path": path}).json()["ok"]
    unsaved = client.post("/api/validate", json={"model": data}).json()   # found in the root?
    assert not unsaved["ok"] and "Axis" in unsaved["problems"][0]["message"]


def test_there_is_no_layout_endpoint(client):
    """The page lays out its diagrams itself (frontend/src/studio/layout.js); the server's
    layout, which the page never asked for and which placed blocks otherwise, is gone."""
    assert client.post("/api/layout", json={"model": seed(client)}).status_code in (404, 405)


# -- runs --------------------------------------------------------------------------------------
def test_a_run_gives_what_kn_simulate_gives(client, root):
    run_id = client.post("/api/run", json={"model": seed(client)}).json()["run"]
    answer = wait(client, run_id)
    assert answer["state"] == "done", answer["error"]
    assert answer["progress"] == 1.0 and answer["error"] is None
    expected = kn.simulate(kn.load(root / SEED))
    results = answer["results"]
    np.testing.assert_allclose(results["t"], expected.t, rtol=0, atol=1e-12)
    assert [s["name"] for s in results["signals"]] == expected.signal_names
    for signal in results["signals"]:
        assert signal["unit"] == expected.units[signal["name"]]
        assert tuple(signal["shape"]) == expected[signal["name"]].shape[1:]
        # the descriptor, so the page never splits names
        described = expected.signals[signal["name"]]
        assert (signal["probe"], signal["quantity"], signal["port"]) == \
            (described.probe, described.quantity, described.target)
        np.testing.assert_allclose(signal["values"], expected[signal["name"]], rtol=0,
                                   atol=1e-12)
    assert results["partial"] is None
    angle = next(s for s in results["signals"] if s["name"] == "probe1.angle")
    assert (angle["probe"], angle["quantity"], angle["port"]) == \
        ("probe1", "angle", "shoulder.axis")


def test_the_plots_results_can_come_ahead_of_the_3d_view(client, root):
    """``?animation=later``: the results for the plots as soon as the child has them (done,
    ``animation_pending``), the 3-D view's poses from ``/animation``; the whole answer, which
    a poll without it gets, holds the same of both."""
    data = client.get("/api/open", params={"path": "models/engine_v6/EngineV6.json"}).json()
    run_id = client.post("/api/run", json={"model": data["model"], "path":
                                           "models/engine_v6/EngineV6.json"}).json()["run"]
    end = time.monotonic() + 120
    while True:
        ahead = client.get(f"/api/run/{run_id}?wait=2&animation=later").json()
        if ahead["state"] != "running" or time.monotonic() > end:
            break
    assert ahead["state"] == "done", ahead["error"]
    while True:
        view = client.get(f"/api/run/{run_id}/animation?wait=2").json()
        if view["state"] != "running" or time.monotonic() > end:
            break
    whole = wait(client, run_id)
    assert whole == client.get(f"/api/run/{run_id}?animation=later").json()   # ended: whole
    assert "animation_pending" not in whole["results"]
    assert view == {"state": "done", "animation": whole["results"]["animation"],
                    "animation_note": None}
    assert view["animation"]["frames"]
    results = ahead["results"]
    if results.get("animation_pending"):       # (else the run had ended meanwhile)
        assert results["animation"] is None and results["animation_note"] is None
        del results["animation_pending"]
        results.update(animation=view["animation"], animation_note=None)
    assert ahead == whole
    assert client.get(f"/api/run/{run_id}?animation=soon").status_code == 400
    assert client.get("/api/run/r999/animation").status_code == 404


def _sends_ahead(channel):
    channel.ahead("results", b'{"state":"done","results":{"t":[0.0]}}')
    time.sleep(1.5)
    channel.ahead("animation", b'{"state":"done","animation":null,"animation_note":"no"}')
    time.sleep(0.5)
    return "done", b'{"state":"done","whole":true}'


def _answers_alone(channel):
    raise RuntimeError("broke")


def test_a_child_s_parts_sent_ahead_come_before_its_answer():
    job = runs.Job("r1", "run", _sends_ahead, ())
    end = time.monotonic() + 60
    while job.ahead("results") is None and time.monotonic() < end:
        time.sleep(0.01)
    assert job.state == "running"
    assert job.body(later=True) == b'{"state":"done","results":{"t":[0.0]}}'
    assert json.loads(job.body())["state"] == "running"
    assert job.animation() == b'{"state":"running"}'
    while job.ahead("animation") is None and time.monotonic() < end:
        time.sleep(0.01)
    assert job.state == "running" and json.loads(job.animation())["animation_note"] == "no"
    job.thread.join(60)
    assert job.state == "done"
    assert job.body() == job.body(later=True) == b'{"state":"done","whole":true}'
    # a run that ends without its 3-D view says why there is none
    failed = runs.Job("r2", "run", _answers_alone, ())
    failed.thread.join(60)
    assert failed.state == "failed" and failed.ahead("results") is None
    assert json.loads(failed.body(later=True))["state"] == "failed"
    assert json.loads(failed.animation()) == {
        "state": "failed", "animation": None,
        "animation_note": "The run ended failed before its 3-D view was made."}


def _stuck_compiling(reported, channel):
    """A child that says it is compiling (having reported progress or not) and does not stop
    when asked: it is ended after the phase's grace."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    channel.enter("compiling")
    if reported:
        channel.report(0.3)
    time.sleep(120)


@pytest.mark.parametrize("reported", [False, True])
def test_a_child_ended_by_a_cancel_says_whether_it_had_computed_anything(reported):
    job = runs.Job("r1", "run", _stuck_compiling, (reported,))
    end = time.monotonic() + 60
    while (job.child.phase != "compiling" or job.child.progress != (0.3 if reported else 0.0)) \
            and time.monotonic() < end:
        time.sleep(0.01)
    job.cancel()
    job.thread.join(60)
    answer = json.loads(job.body())
    assert job.state == answer["state"] == "cancelled" and answer["results"] is None
    assert answer["note"] == ("stopped while compiling: what it had computed could not be kept"
                              if reported else "stopped while compiling: nothing had been "
                                               "computed yet")


def test_results_carry_the_animation(client):
    settings = {"t_end": 0.5, "n_points": 6}
    answer = wait(client, client.post("/api/run", json={"model": seed(client),
                                                        "settings": settings}).json()["run"])
    animation = answer["results"]["animation"]
    assert animation["format"] == "kinetwork.animation" and animation["frames"]
    assert len(animation["t"]) == 6 and answer["results"]["animation_note"] is None


def test_without_the_animation_module_results_say_why_there_is_no_3d_view(root, monkeypatch):
    model = kn.load(root / SEED)
    res = kn.simulate(model, t_end=0.5, n_points=6)
    monkeypatch.setitem(sys.modules, "kinetwork.animation", None)     # not importable
    out = results.results_json(res, model)
    assert out["animation"] is None and "not installed" in out["animation_note"]


@pytest.mark.parametrize("writer", ["orjson", "json"])
def test_answers_are_the_same_json_by_either_writer(root, monkeypatch, writer):
    """A run's answer, with the numbers left as numpy arrays (signals, poses), read back is
    what json writes of the same content as lists: NaN and infinities null, keys that are
    not strings as strings, an integer past 64 bits and an array of every other point as
    json writes them; by orjson (the studio's extras) or json (without it)."""
    import orjson
    assert results.orjson is orjson
    if writer == "json":
        monkeypatch.setattr(results, "orjson", None)
    model = kn.load(root / SEED)
    res = kn.simulate(model, t_end=0.5, n_points=6)
    content = results.results_json(res, model)
    assert isinstance(content["signals"][0]["values"], np.ndarray)
    assert isinstance(content["animation"]["frames"][0]["position"], np.ndarray)
    content["signals"][0]["values"][1:3] = [np.nan, -np.inf]
    content["extra"] = {1: np.arange(6.0)[::2], "x": np.float64(0.1), "n": np.int64(3),
                        "nested": [np.array([[1.5, np.inf]])]}
    got = json.loads(results.encode(content))
    assert results.encode({"big": [2**70, np.nan]}) == b'{"big":[1180591620717411303424,null]}'
    # what json writes of it: lists, non-finite numbers null, keys as strings
    assert got == json.loads(json.dumps(plain(content), allow_nan=False))
    assert got["signals"][0]["values"][1:3] == [None, None]


def test_a_dense_run_is_resampled_for_the_animation(root, monkeypatch):
    monkeypatch.setattr(results, "MAX_FRAMES", 50)
    model = kn.load(root / SEED)
    out = results.results_json(kn.simulate(model, t_end=2.0, n_points=201), model)
    assert len(out["t"]) == 201 and len(out["animation"]["t"]) == 50


@pytest.mark.parametrize("name", ["msl_friction.json", "robot_r3/OneAxis.json"])
def test_a_1d_model_runs_and_says_the_3d_view_has_nothing_to_show(client, name, caplog):
    data = client.get("/api/open", params={"path": f"models/{name}"}).json()["model"]
    answer = wait(client, client.post("/api/run", json={"model": data, "settings": {
        "n_points": 11, "t_end": 0.1}, "path": f"models/{name}"}).json()["run"])
    assert answer["state"] == "done", answer["error"]
    assert answer["results"]["animation"] is None
    assert answer["results"]["animation_note"] == results.NO_SCENE
    assert not [r for r in caplog.records if r.levelname in ("WARNING", "ERROR")]


def test_run_settings_override_the_models(client):
    settings = {"t_end": 0.5, "n_points": 11, "method": "rk", "step": 0.01}
    answer = wait(client, client.post("/api/run", json={"model": seed(client),
                                                        "settings": settings}).json()["run"])
    assert answer["state"] == "done"
    assert answer["results"]["t"] == pytest.approx(np.linspace(0, 0.5, 11).tolist())


def test_cancel_ends_a_long_run_cancelled_with_partial_results(client):
    settings = {"t_end": 1e6, "n_points": 100001, "rtol": 1e-12, "atol": 1e-14}
    run_id = client.post("/api/run", json={"model": seed(client),
                                           "settings": settings}).json()["run"]
    end = time.monotonic() + 60
    while client.get(f"/api/run/{run_id}").json()["progress"] == 0 and time.monotonic() < end:
        time.sleep(0.05)
    assert client.post(f"/api/run/{run_id}/cancel").json() == {"ok": True}
    answer = wait(client, run_id, timeout=30)
    assert answer["state"] == "cancelled" and answer["error"] is None
    partial = answer["results"]
    assert 1 < len(partial["t"]) < 100001 and partial["partial"]["reason"] == "cancelled"
    assert len(partial["signals"][0]["values"]) == len(partial["t"])


def test_a_failed_integration_ends_failed_with_its_message_and_partial_results(client):
    stiff = seed(client)
    stiff["parameters"]["c"] = 1e9
    run_id = client.post("/api/run", json={"model": stiff, "settings": {
        "method": "rk", "step": 0.01}}).json()["run"]
    answer = wait(client, run_id)
    assert answer["state"] == "failed" and "non-finite" in answer["error"]
    assert answer["results"]["partial"]["t_reached"] < 10
    json.dumps(answer, allow_nan=False)


def test_a_time_limit_ends_a_run_failed(client):
    answer = wait(client, client.post("/api/run", json={
        "model": seed(client), "settings": {"time_limit": 1e-6}}).json()["run"])
    assert answer["state"] == "failed" and "time limit" in answer["error"]


def test_a_bad_model_fails_its_run_with_problems(client):
    answer = wait(client, client.post("/api/run", json={
        "model": with_params(seed(client), "mass1", mass=-1)}).json()["run"])
    assert answer["state"] == "failed" and answer["results"] is None
    assert [(p["component"], p["param"]) for p in answer["problems"]] == [("mass1", "mass")]
    answer = wait(client, client.post("/api/run", json={
        "model": seed(client), "settings": {"t_end": "soon"}}).json()["run"])
    assert answer["state"] == "failed" and "t_end" in answer["error"]


def test_concurrent_runs(client, root):
    starts = [0.05, 0.3, 1.0]
    settings = {"t_end": 2.0, "n_points": 201}
    ids = [client.post("/api/run", json={"model": with_params(seed(client), "shoulder", q0=q0),
                                         "settings": settings}).json()["run"]
           for q0 in starts]
    assert len(set(ids)) == 3
    for run_id, q0 in zip(ids, starts):
        answer = wait(client, run_id)
        assert answer["state"] == "done", answer["error"]
        model = kn.load(root / SEED)
        model.components["shoulder"].q0 = q0
        angle = next(s for s in answer["results"]["signals"] if s["name"] == "probe1.angle")
        np.testing.assert_allclose(angle["values"], kn.simulate(model, **settings)
                                   ["probe1.angle"], rtol=0, atol=1e-12)


def test_runs_unknown_are_404(client):
    assert client.get("/api/run/r999").status_code == 404
    assert client.post("/api/run/r999/cancel").status_code == 404


def test_only_the_last_finished_runs_are_kept(client):
    client.app.state.studio.runs.keep = 2
    body = {"model": seed(client), "settings": {"t_end": 0.1, "n_points": 3}}
    ids = []
    for _ in range(4):
        ids.append(client.post("/api/run", json=body).json()["run"])
        wait(client, ids[-1])
    assert [client.get(f"/api/run/{i}").status_code for i in ids] == [404, 404, 200, 200]


def test_runs_going_at_once_are_limited(client):
    client.app.state.studio.runs.max_running = 1
    long = {"model": seed(client), "settings": {"t_end": 1e6, "n_points": 100001}}
    first = client.post("/api/run", json=long).json()["run"]
    answer = client.post("/api/run", json=long)
    assert answer.status_code == 409 and "going" in answer.json()["error"]
    client.post(f"/api/run/{first}/cancel")
    assert wait(client, first, timeout=30)["state"] == "cancelled"
    assert client.post("/api/run", json={**long, "settings": {"t_end": 0.1}}).status_code == 200


# -- malformed requests --------------------------------------------------------------------------
BIG = "1" + "0" * 400
MALFORMED = [
    ("/api/validate", b"not json"), ("/api/validate", b"[1, 2]"), ("/api/validate", b"{}"),
    ("/api/validate", b'{"model": 1}'), ("/api/validate", b'{"model": {}, "extra": 1}'),
    ("/api/validate", b'{"model": {"components": "x"}}'),
    ("/api/validate", b'{"model": {"format": "kinetwork.model", "version": 1, "name": "m", '
                      b'"components": [{"name": "g", "type": "multibody.Ground", "params": '
                      b'{"gravity": [0, 1e308, 1e308]}}]}}'),
    ("/api/validate", ('{"model": {"format": "kinetwork.model", "version": 1, "name": "m", '
                       '"components": [], "parameters": {"a": ' + BIG + '}}}').encode()),
    ("/api/validate", b'{"model": {"version": NaN}}'),
    ("/api/validate", b"[" * 100000 + b"]" * 100000),
    ("/api/validate", b'{"model": {"format": "kinetwork.model", "version": 1, "name": "m", '
                      b'"components": [null, 1, {"name": []}], "connections": [[1, 2], "a"]}}'),
    ("/api/validate", b'{"model": {}, "path": 5}'),
    ("/api/save", b'{"path": "a.json"}'), ("/api/save", b'{"path": 1, "model": {}}'),
    ("/api/save", b'{"path": "a.json", "model": {}, "text": 5}'),
    ("/api/save", b'{"path": "a.json", "model": [], "text": null}'),
    ("/api/run", b'{"model": {}, "settings": []}'),
    ("/api/run", b'{"model": {}, "settings": {"speed": 1}}'),
    ("/api/run", b'{"settings": {}}'),
    ("/api/open?path=", b""), ("/api/open?path=a.json&example=x", b""),
]


@pytest.mark.parametrize("route, body", MALFORMED,
                         ids=[f"{i}-{r}" for i, (r, _) in enumerate(MALFORMED)])
def test_malformed_requests_are_refused_not_crashed(client, route, body):
    if route.startswith("/api/open"):
        answer = client.get(route)
    else:
        answer = client.post(route, content=body, headers={"content-type": "application/json"})
    assert answer.status_code in (200, 400, 404, 409), answer.text
    data = answer.json()
    if answer.status_code != 200:
        assert isinstance(data["error"], str) and isinstance(data["problems"], list)
    else:
        assert isinstance(data["ok"], bool)          # validate: said, not raised


@pytest.mark.parametrize("settings", [
    {"t_end": 1e308}, {"n_points": 10**15}, {"rtol": -1}, {"method": "nope"},
    {"step": 1e-300, "method": "rk"}, {"max_steps": "x"}, {"n_points": 2.5},
    {"time_limit": -1}, {"t_end": True},
])
def test_bad_settings_fail_the_run_with_a_message(client, settings):
    answer = wait(client, client.post("/api/run", json={"model": seed(client),
                                                        "settings": settings}).json()["run"])
    assert answer["state"] == "failed" and answer["error"], answer


# -- the real server and the command -------------------------------------------------------------
def test_the_server_answers_over_http(root):
    with serving(create_app(root, TOKEN)) as port:        # and stops when asked
        base = f"http://127.0.0.1:{port}"
        answer = httpx.get(f"{base}/api/palette", headers={TOKEN_HEADER: TOKEN}, timeout=20)
        assert answer.status_code == 200
        assert {t["type"] for lib in answer.json()["libraries"] for t in lib["types"]} == \
            set(REGISTRY)
        assert httpx.get(f"{base}/api/palette", timeout=20).status_code == 403


def test_cli_studio_prints_the_address_and_serves_the_folder(root, monkeypatch, capsys):
    served = {}

    def run(self, sockets):
        served["app"], served["port"] = self.config.app, sockets[0].getsockname()[1]
        raise KeyboardInterrupt           # as Ctrl-C ends uvicorn: exit 0
    monkeypatch.setattr(uvicorn.Server, "run", run)
    monkeypatch.setattr(launch.webbrowser, "open", lambda url: served.setdefault("url", url))
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.chdir(root)
    args = types.SimpleNamespace(model=SEED, port=None, no_browser=False, library=[])
    assert launch.cli_studio(args) == 0
    out = capsys.readouterr().out
    assert f"http://127.0.0.1:{served['port']}/?token=" in out
    assert "&open=models%2Fdouble_pendulum.json" in out and served["url"] in out
    token = served["url"].split("token=")[1].split("&")[0]
    assert len(token) >= 40
    c = TestClient(served["app"])
    assert c.get("/api/files", params={"token": token}).json()["open"] == SEED


def test_cli_studio_opens_no_text_browser_without_a_display(monkeypatch, capsys):
    monkeypatch.setattr(launch.webbrowser, "open", lambda url: pytest.fail("opened"))
    monkeypatch.setattr(launch.sys, "platform", "linux")
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "BROWSER"):
        monkeypatch.delenv(name, raising=False)
    launch._open_browser("http://127.0.0.1:1/")
    assert "open the address" in capsys.readouterr().out


def test_cli_studio_roots_a_model_outside_the_folder_at_its_own(root, tmp_path_factory,
                                                                monkeypatch):
    monkeypatch.chdir(tmp_path_factory.mktemp("elsewhere"))
    assert launch._root_and_query(str(root / SEED)) == \
        (os.path.realpath(root / "models"), {"open": "double_pendulum.json"})
    assert launch._root_and_query("double_pendulum")[1] == {"example": "double_pendulum"}
    with pytest.raises(kn.ModelError, match="no such file, nor an example"):
        launch._root_and_query("nope.json")


def test_cli_studio_without_its_extras_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "uvicorn", None)
    args = types.SimpleNamespace(model=None, port=None, no_browser=True, library=[])
    with pytest.raises(kn.ModelError, match=r"pip install 'kinetwork\[studio\]'"):
        launch.cli_studio(args)


def test_cli_studio_refuses_a_port_in_use():
    sock = launch._listen(None)
    try:
        with pytest.raises(kn.ModelError, match="cannot listen"):
            launch._listen(sock.getsockname()[1])
    finally:
        sock.close()
