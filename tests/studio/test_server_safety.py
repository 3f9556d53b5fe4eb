"""The studio's server under attack (issue 26, the studio's side): special files in its folder
block nothing, a model that makes unbounded work in its checks holds up no other request and
is ended, SIGINT stops the server while such work is under way, results too large for the page
are refused up front, a cancel stops a run in every phase keeping what it reached, and saves
never replace a file changed since it was read.

Times are not asserted: what is checked is the order of events (another request answered
while a check is still going) and that nothing hangs (a generous timeout, printed figures)."""

import json
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import httpx
import pytest

import kinetwork as kn
from kinetwork.studio import files
from kinetwork.studio.server import TOKEN_HEADER, create_app
from tests.studio.helpers import serving

TOKEN = "safety-token-0123456789"
SEED = "models/double_pendulum.json"
#: a unit whose exponent is a tower: checking it is unbounded work without a bound
TOWER = "1 kg^100^100^100"


@pytest.fixture
def live(root):
    """The studio over HTTP (uvicorn in a thread), and an httpx client of it."""
    with serving(create_app(root, TOKEN)) as port, \
            httpx.Client(base_url=f"http://127.0.0.1:{port}", headers={TOKEN_HEADER: TOKEN},
                         timeout=120) as client:
        yield client


def seed(client):
    return client.get("/api/open", params={"path": SEED}).json()["model"]


def with_mass(data, mass):
    data = json.loads(json.dumps(data))
    next(c for c in data["components"] if c["name"] == "mass1")["params"]["mass"] = mass
    return data


def wait(client, kind, job_id, timeout=300.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        answer = client.get(f"/api/{kind}/{job_id}").json()
        if answer["state"] != "running":
            return answer
        time.sleep(0.05)
    raise AssertionError(f"{kind} {job_id} still going after {timeout} s")


# -- special files ------------------------------------------------------------------------------
@pytest.fixture
def fifo(root):
    path = root / "pipe.json"
    os.mkfifo(path)
    return path


def test_a_fifo_in_the_folder_blocks_nothing(live, root, fifo):
    listed = live.get("/api/files").json()["files"]
    assert "pipe.json" not in listed and SEED in listed
    for _ in range(50):                            # more opens than the server has threads
        answer = live.get("/api/open", params={"path": "pipe.json"})
        assert answer.status_code == 400 and "FIFO" in answer.json()["error"]
    data = seed(live)
    answer = live.post("/api/save", json={"path": "pipe.json", "model": data})
    assert answer.status_code in (400, 409) and fifo.is_fifo()
    # a model placing a definition named like the FIFO: not a definition file, said at once
    data["components"].append({"name": "p", "type": "pipe", "params": {}})
    problems = live.post("/api/validate", json={"model": data}).json()["problems"]
    assert any(p["component"] == "p" and "pipe" in p["message"] for p in problems), problems
    assert live.get("/api/palette").status_code == 200


def test_a_save_onto_a_special_file_refuses_and_leaves_it(live, root):
    sock_path = root / "sock.json"
    import socket
    s = socket.socket(socket.AF_UNIX)
    s.bind(str(sock_path))
    try:
        answer = live.post("/api/save", json={"path": "sock.json", "model": seed(live)})
        assert answer.status_code in (400, 409)
        assert pathlib.Path(sock_path).is_socket()
    finally:
        s.close()


# -- unbounded checks ---------------------------------------------------------------------------
def test_a_power_tower_in_validate_holds_up_no_other_request(live, monkeypatch):
    data = with_mass(seed(live), TOWER)
    done = {}

    def check():
        done["answer"] = live.post("/api/validate", json={"model": data}).json()
        done["at"] = time.monotonic()
    worker = threading.Thread(target=check)
    started = time.monotonic()
    worker.start()
    time.sleep(0.3)                                # the check is under way
    answered = []
    for route in ("/api/palette", "/api/files", "/api/examples", "/api/facts"):
        assert live.get(route).status_code == 200
        answered.append(time.monotonic())
    other = live.post("/api/validate", json={"model": seed(live)}).json()
    assert other["ok"]
    answered.append(time.monotonic())
    worker.join(120)
    answer = done["answer"]
    assert not answer["ok"] and answer["problems"]
    # the other requests were answered while it went on, or it was bounded by the library
    assert all(t < done["at"] for t in answered) or "mass" in answer["problems"][0]["message"]
    print(f"\nvalidate of {TOWER!r}: answered in {done['at'] - started:.1f} s "
          f"({answer['problems'][0]['message'][:100]!r}); other requests meanwhile in "
          f"{max(answered) - started:.2f} s")


def test_sigint_stops_the_server_while_a_check_is_under_way(root):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "kinetwork", "studio", "--no-browser"],
                            cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=env)
    client = None
    try:
        url = None
        for _ in range(200):
            line = proc.stdout.readline()
            if "token=" in line:
                url = line.strip()
                break
        assert url, "the studio printed no address"
        base, query = url.split("/?")
        token = query.split("token=")[1].split("&")[0]
        client = httpx.Client(base_url=base, headers={TOKEN_HEADER: token}, timeout=60)
        data = client.get("/api/open", params={"path": SEED}).json()["model"]
        check = threading.Thread(target=lambda: _quietly(client.post, "/api/validate",
                                                         json={"model": with_mass(data, TOWER)}),
                                 daemon=True)
        check.start()
        run_id = client.post("/api/run", json={"model": data, "settings": {
            "t_end": 1e6, "n_points": 100001, "rtol": 1e-12}}).json()["run"]
        time.sleep(1.0)
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        code = proc.wait(60)                         # a hang fails here
        print(f"\nSIGINT to exit with a check and a run under way: "
              f"{time.monotonic() - sent:.2f} s (exit code {code})")
        assert code == 0
        assert run_id
        check.join(60)                           # the check's request ended with the server
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()
        if client is not None:                   # its sockets closed here, not at some later gc
            client.close()


def _quietly(call, *args, **kwargs):
    try:
        call(*args, **kwargs)
    except httpx.HTTPError:
        pass


# -- bounded results ------------------------------------------------------------------------------
def test_a_run_of_five_million_points_is_refused_before_it_runs(live):
    run_id = live.post("/api/run", json={"model": seed(live),
                                         "settings": {"n_points": 5_000_001}}).json()["run"]
    answer = wait(live, "run", run_id, timeout=120)
    assert answer["state"] == "failed" and answer["results"] is None
    assert "n_points" in answer["error"] and "more than the studio plots" in answer["error"]
    assert answer["phase"] == "checking"                 # before even compiling
    # fewer, still too many for this model's probes: refused once compiled, with the most
    run_id = live.post("/api/run", json={"model": seed(live),
                                         "settings": {"n_points": 200_001}}).json()["run"]
    answer = wait(live, "run", run_id, timeout=120)
    assert answer["state"] == "failed" and answer["phase"] == "compiling"
    most = int(answer["error"].split("give at most ")[1].split(" points")[0].replace(",", ""))
    assert most == 1_000_000 // 9                      # the time and eight probe quantities
    assert live.get("/api/palette").status_code == 200


def test_a_sweep_too_large_is_refused_before_it_runs(live):
    answer = live.post("/api/sweep", json={"model": seed(live), "sweep": {
        "kind": "grid", "grid": {"c": list(range(1, 11)), "d": list(range(1, 11))}}}).json()
    final = wait(live, "sweep", answer["sweep"], timeout=120)
    assert final["state"] == "failed" and "at most 64" in final["error"]


# -- cancel in every phase ---------------------------------------------------------------------
def test_cancel_while_compiling_ends_the_run_at_once(live, monkeypatch, tmp_path):
    # a cold cache of its own (the child takes the server's KINETWORK_ settings when it
    # starts): with the suite's shared one warm, EngineV6 compiles in a blink and the first
    # chunk is integrated before the cancel comes (it then keeps what it reached)
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path))
    data = live.get("/api/open", params={"example": "engine_v6/EngineV6"}).json()["model"]
    run_id = live.post("/api/run", json={"model": data}).json()["run"]
    end = time.monotonic() + 300
    while time.monotonic() < end:
        answer = live.get(f"/api/run/{run_id}").json()
        if answer["state"] != "running" or answer["phase"] == "compiling":
            break
        time.sleep(0.02)
    assert answer["phase"] == "compiling", answer
    sent = time.monotonic()
    assert live.post(f"/api/run/{run_id}/cancel").json() == {"ok": True}
    now = live.get(f"/api/run/{run_id}").json()
    assert now.get("cancelling") is True or now["state"] == "cancelled"
    answer = wait(live, "run", run_id, timeout=60)
    print(f"\ncancel while compiling EngineV6: ended in {time.monotonic() - sent:.2f} s")
    assert answer["state"] == "cancelled" and answer["results"] is None


def test_cancel_in_the_integration_keeps_what_it_reached(live):
    run_id = live.post("/api/run", json={"model": seed(live), "settings": {
        "t_end": 1e6, "n_points": 100001, "rtol": 1e-12, "atol": 1e-14}}).json()["run"]
    end = time.monotonic() + 300
    while time.monotonic() < end:
        answer = live.get(f"/api/run/{run_id}").json()
        if answer["progress"] > 0:
            break
        time.sleep(0.05)
    progress = answer["progress"]
    sent = time.monotonic()
    live.post(f"/api/run/{run_id}/cancel")
    answer = wait(live, "run", run_id, timeout=120)
    print(f"\ncancel while integrating: ended in {time.monotonic() - sent:.2f} s")
    assert answer["state"] == "cancelled"
    reached = answer["results"]["partial"]["t_reached"]
    assert answer["results"]["partial"]["reason"] == "cancelled"
    assert reached < 1e6 * min(1.0, progress + 0.25)
    assert len(answer["results"]["t"]) == len(answer["results"]["signals"][0]["values"])


def test_a_cancel_of_a_finished_run_changes_nothing(live):
    run_id = live.post("/api/run", json={"model": seed(live),
                                         "settings": {"t_end": 0.5, "n_points": 11}}).json()["run"]
    finished = wait(live, "run", run_id)
    assert finished["state"] == "done"
    assert live.post(f"/api/run/{run_id}/cancel").json() == {"ok": True}
    assert live.get(f"/api/run/{run_id}").json() == finished


# -- saves: versions ------------------------------------------------------------------------------
def test_a_save_based_on_an_old_version_is_refused_and_the_file_kept(live, root):
    opened = live.get("/api/open", params={"path": SEED}).json()
    other = json.loads(opened["text"])
    other["description"] = "theirs"
    (root / SEED).write_text(json.dumps(other))
    theirs = (root / SEED).read_bytes()
    mine = with_mass(opened["model"], 2.0)
    answer = live.post("/api/save", json={"path": SEED, "model": mine,
                                          "base": opened["version"]})
    assert answer.status_code == 409
    assert answer.json()["conflict"]["version"] == files.version_of(theirs)
    assert (root / SEED).read_bytes() == theirs
    # overwriting names the version it replaces
    answer = live.post("/api/save", json={"path": SEED, "model": mine,
                                          "base": answer.json()["conflict"]["version"]})
    assert answer.status_code == 200
    assert kn.load(root / SEED).components["mass1"].given["mass"] == 2.0
    # a new file: base null; one that appeared meanwhile is not replaced
    (root / "new.json").write_text(opened["text"])
    answer = live.post("/api/save", json={"path": "new.json", "model": mine, "base": None})
    assert answer.status_code == 409 and answer.json()["conflict"]["version"]
    # a file removed since: said so
    (root / "new.json").unlink()
    answer = live.post("/api/save", json={"path": "new.json", "model": mine,
                                          "base": opened["version"]})
    assert answer.status_code == 409 and answer.json()["conflict"]["version"] is None


def test_concurrent_saves_of_one_version_let_one_through(live, root):
    opened = live.get("/api/open", params={"path": SEED}).json()
    answers = []

    def save(mass):
        answers.append(live.post("/api/save", json={
            "path": SEED, "model": with_mass(opened["model"], mass),
            "base": opened["version"]}).status_code)
    threads = [threading.Thread(target=save, args=(m,)) for m in (2.0, 3.0, 4.0, 5.0)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert sorted(answers) == [200, 409, 409, 409]


def test_autosave_never_replaces_a_file_it_did_not_write(live, root):
    hidden = root / "models" / ".double_pendulum.json.kinetwork-recovery"
    hidden.write_text("my notes")
    answer = live.post("/api/autosave", json={"path": SEED, "model": seed(live), "base": None})
    assert answer.status_code == 409 and hidden.read_text() == "my notes"
    assert live.get("/api/recovery", params={"path": SEED}).json() == {"recovery": None}
    live.post("/api/recovery/discard", json={"path": SEED})
    assert hidden.read_text() == "my notes"


def test_runs_under_way_end_with_the_server(root):
    """The server's shutdown ends the children at work (none goes on orphaned)."""
    import warnings
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Using `httpx` with `starlette.testclient`")
        from fastapi.testclient import TestClient
    with TestClient(create_app(root, TOKEN), headers={TOKEN_HEADER: TOKEN}) as client:
        run_id = client.post("/api/run", json={"model": seed(client), "settings": {
            "t_end": 1e6, "n_points": 100001, "rtol": 1e-12}}).json()["run"]
        job = client.app.state.studio.runs.get(run_id)
        time.sleep(0.5)
        assert job.child.process.is_alive()
    job.child.process.join(10)
    assert not job.child.process.is_alive()
