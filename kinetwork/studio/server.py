"""The studio's HTTP server: the API of ``API.md`` over kinetwork, and the built front end.

``create_app(root, token)`` gives an ASGI app (FastAPI). Every ``/api`` route checks the
session token; files are read and written only inside ``root``, special files (FIFOs,
devices) never opened, a save refused when the file changed since the page read it. Whatever
reads a model the page sent (check, lay out, write, run, sweep, linearise) runs in a child
process (``jobs``), with a time limit, so no request holds up another and SIGINT stops the
server at once. Answers are JSON, a refusal ``{"error", "problems"}`` with 400, 403, 404,
409 or 503, never a traceback.
"""

import asyncio
import contextlib
import json
import logging
import os
import pathlib
import secrets
import time

from fastapi import APIRouter, Depends, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException

from ..errors import ModelError
from ..graph.io import FORMAT, MAX_FILE_SIZE, load
from ..graph.writer import dumps
from ..schema import schema
from . import checks, files, jobs, work
from .facts import facts
from .files import Conflict, StudioError
from .results import encode
from .runs import Runs, check_settings

log = logging.getLogger("kinetwork.studio")

STATIC = pathlib.Path(__file__).resolve().parent / "static"
TOKEN_HEADER = "X-Kinetwork-Token"
#: the largest request body: a model file's limit, and room for its JSON around it
MAX_BODY = 2 * MAX_FILE_SIZE
#: seconds a check (validate, layout, the text of a save) may take before it is stopped; the
#: compilation validate does to count states (a model that checks: its answer waits for it,
#: or goes without the counts); and a linearisation (it may simulate up to its time)
CHECK_LIMIT, SUMMARY_LIMIT, LINEARIZE_LIMIT = 15.0, 30.0, 120.0
#: checks in child processes at once; more wait their turn (up to their time limit)
MAX_CHECKS = 4
#: the longest a poll of a run waits for it to end
MAX_WAIT = 2.0


class StudioJSON(JSONResponse):
    """JSON as the page reads it: compact, numpy values as lists, NaN and infinities null
    (JSON has none, and a model file or partial results may hold them)."""

    def render(self, content):
        return encode(content)


def create_app(root, token, library=None, model=None, static=None):
    """The studio as an ASGI app.

    Parameters
    ----------
    root : str or os.PathLike
        The folder every path of the API is relative to; nothing outside it is read or
        written (the examples apart, which are only read).
    token : str
        The session token every ``/api`` request and the page must carry (query parameter
        ``token`` or header ``X-Kinetwork-Token``).
    library : list of folders, optional
        Subsystem library folders, as ``kn.load(..., library=)``.
    model : str, optional
        The model file the studio was started with (relative to ``root``, or absolute inside
        it); ``GET /api/files`` names it as ``open``.
    static : str or os.PathLike, optional
        The folder of the built page to serve (default: the package's ``static``); the
        end-to-end tests serve their own build, with its test hook.

    Returns
    -------
    fastapi.FastAPI
    """
    if not isinstance(token, str) or not token:
        raise ModelError("the studio needs a token")
    studio = _Studio(os.path.realpath(os.fspath(root)), token, list(library or []))
    if model is not None:
        path = os.fspath(model)
        rel = os.path.relpath(os.path.realpath(path), studio.root) if os.path.isabs(path) \
            else path
        try:
            studio.open = files.confine(studio.root, rel, "model")[1]
        except StudioError as exc:
            raise ModelError(exc.message) from None

    static = pathlib.Path(static) if static is not None else STATIC

    @contextlib.asynccontextmanager
    async def lifespan(app):
        jobs.warm_up()
        yield
        studio.runs.stop_all()

    app = FastAPI(title="kinetwork studio", docs_url=None, redoc_url=None, openapi_url=None,
                  default_response_class=StudioJSON, lifespan=lifespan)
    app.state.studio = studio
    _handlers(app)
    api = APIRouter(prefix="/api", dependencies=[Depends(studio.check_token)])
    _routes(api, studio)
    app.include_router(api)

    @app.get("/", dependencies=[Depends(studio.check_token)], include_in_schema=False)
    def page():
        index = static / "index.html"
        if index.is_file():
            return FileResponse(index, headers={"Cache-Control": "no-store"})
        return HTMLResponse(PLACEHOLDER)

    @app.get("/assets/{name:path}", include_in_schema=False)
    def asset(name: str):
        # no token: the page's scripts and styles are the same for everyone; only the built
        # files are served, and nothing the path could reach outside their folder
        if "\x00" in name or len(name) > 255:       # realpath raises on a NUL
            raise StudioError(404, f"no asset {name!r:.80}")
        folder = os.path.realpath(static / "assets")
        path = os.path.realpath(os.path.join(folder, name))
        if os.path.commonpath([path, folder]) != folder or not os.path.isfile(path):
            raise StudioError(404, f"no asset {name!r:.80}")
        return FileResponse(path, headers={"Cache-Control": "public, max-age=3600"})

    return app


class _Studio:
    """What the routes share: the root, the token, the library folders, the runs."""

    def __init__(self, root, token, library):
        self.root, self.token, self.library = root, token, library
        self.open = None
        self.runs = Runs()
        self._checks = None

    async def call(self, fn, *args, limit=CHECK_LIMIT, what="checking the model"):
        """``fn(*args, channel)`` in a child process, awaited (at most MAX_CHECKS at once).

        Raises
        ------
        StudioError
            503 when it took longer than ``limit`` seconds (the child is ended), or waited
            that long for its turn; 500 when the child failed.
        """
        if self._checks is None:
            self._checks = asyncio.Semaphore(MAX_CHECKS)
        try:
            await asyncio.wait_for(self._checks.acquire(), limit)
        except asyncio.TimeoutError:
            raise StudioError(503, f"{what}: the studio is busy with {MAX_CHECKS} other "
                                   f"checks; try again") from None
        try:
            child = jobs.Child(fn, args)
            return await child.answer_async(limit)
        except jobs.TimeLimit:
            raise StudioError(503, f"{what} took longer than {limit:g} s and was stopped: "
                                   f"something in it makes too much work (a unit or an "
                                   f"expression raised to huge powers, a subsystem placing "
                                   f"itself many times over?)") from None
        except jobs.ChildError as exc:
            if exc.kind == "ModelError":
                raise StudioError(400, exc.text) from None
            log.error("%s failed in its worker: %s", what, exc)
            raise StudioError(500, f"{what} failed: internal error ({exc.kind}); the "
                                   f"server's log has the details") from None
        finally:
            self._checks.release()

    def check_token(self, request: Request):
        given = request.headers.get(TOKEN_HEADER) or request.query_params.get("token") or ""
        if not secrets.compare_digest(given.encode("utf-8", "replace"),
                                      self.token.encode("utf-8")):
            raise StudioError(403, "missing or wrong token: open the address that "
                                   "`kinetwork studio` printed")

    def folder(self, real_path=None):
        """The folder a model's definitions are found in (its file's, or the root)."""
        return checks.folder_of(self.root, real_path)

    def model_path(self, body):
        """The real path of the body's optional ``path`` (None when not given)."""
        rel = body.get("path")
        return None if rel is None else files.confine(self.root, rel)[0]


def _routes(api, studio):
    @api.get("/palette")
    def palette():
        return StudioJSON(checks.palette())

    @api.get("/schema")
    def model_schema():
        return StudioJSON(schema())

    @api.get("/facts")
    def studio_facts():
        return StudioJSON(facts())

    @api.get("/files")
    def list_files():
        return StudioJSON({"root": studio.root, "files": files.list_files(studio.root),
                           "open": studio.open})

    @api.get("/examples")
    def examples():
        return StudioJSON({"examples": sorted(files.examples())})

    @api.get("/open")
    def open_file(path: str = None, example: str = None):
        if (path is None) == (example is None):
            raise StudioError(400, "open: give either path= or example=")
        if example is not None:
            return StudioJSON(_open_example(example, studio))
        real, rel = files.confine(studio.root, path)
        raw = files.read_bytes(real, rel)
        text = files.decode(raw, rel)
        return StudioJSON({"path": rel, "text": text, "version": files.version_of(raw),
                           "model": files.parse_model_text(text, rel)})

    @api.post("/validate")
    async def validate(body: dict = Depends(_body)):
        _keys(body, "validate", required=("model",), optional=("path",))
        data = _model(body)
        folder = studio.folder(studio.model_path(body))
        try:
            answer = await studio.call(work.check, data, folder, studio.library)
        except StudioError as exc:
            if exc.status != 503:
                raise
            return StudioJSON({"ok": False, "summary": None, "warnings": [],
                               "problems": [checks.problem(exc.message)]})
        if answer.pop("compile"):
            try:
                more = await studio.call(work.summarize, data, folder, studio.library,
                                         limit=SUMMARY_LIMIT, what="counting the states")
            except StudioError as exc:      # too long to count: the check's answer stands
                if exc.status != 503:
                    raise
                more = {"summary": {}, "warnings": []}
            if more.get("problems"):
                answer.update(ok=False, problems=more["problems"])
            else:
                answer["summary"].update(more["summary"])
                answer["warnings"] = more["warnings"]
        return StudioJSON(answer)

    @api.post("/save")
    async def save(body: dict = Depends(_body)):
        _keys(body, "save", required=("path", "model"), optional=("text", "base"))
        return StudioJSON(await _save(studio, body))

    @api.post("/autosave")
    async def autosave(body: dict = Depends(_body)):
        _keys(body, "autosave", required=("model",), optional=("path", "base", "session"))
        rel = _rel_or_none(studio, body.get("path"))
        base, session = _base(body), body.get("session")
        if session is not None and (not isinstance(session, str) or len(session) > 100):
            raise StudioError(400, "session: a string naming the page's session, or null")
        await run_in_threadpool(files.write_recovery, studio.root, rel, _model(body), base,
                                session)
        return StudioJSON({"ok": True})

    @api.get("/recovery")
    def recovery(path: str = None):
        rel = _rel_or_none(studio, path)
        return StudioJSON({"recovery": files.read_recovery(studio.root, rel)})

    @api.post("/recovery/discard")
    def discard(body: dict = Depends(_body)):
        _keys(body, "recovery/discard", required=(), optional=("path",))
        files.discard_recovery(studio.root, _rel_or_none(studio, body.get("path")))
        return StudioJSON({"ok": True})

    @api.post("/run")
    def run(body: dict = Depends(_body)):
        _keys(body, "run", required=("model",), optional=("settings", "path"))
        data = _model(body)
        settings = check_settings(body.get("settings"))
        started = studio.runs.start("run", data, settings, studio.folder(studio.model_path(body)),
                                    studio.library)
        return StudioJSON({"run": started.id})

    @api.get("/run/{run_id}")
    async def poll(run_id: str, wait: float = 0.0, animation: str = "with"):
        if animation not in ("with", "later"):
            raise StudioError(400, f"animation: 'with' (the default) or 'later', got "
                                   f"{animation!r:.40}")
        later = animation == "later"
        job = studio.runs.get(run_id, "run")
        await _waited(job, wait, lambda: later and job.ahead("results") is not None)
        return Response(job.body(later), media_type="application/json")

    @api.get("/run/{run_id}/animation")
    async def poll_animation(run_id: str, wait: float = 0.0):
        job = studio.runs.get(run_id, "run")
        await _waited(job, wait, lambda: job.ahead("animation") is not None)
        return Response(job.animation(), media_type="application/json")

    @api.post("/run/{run_id}/cancel")
    def cancel(run_id: str):
        studio.runs.get(run_id, "run").cancel()
        return StudioJSON({"ok": True})

    @api.post("/sweep")
    def sweep(body: dict = Depends(_body)):
        _keys(body, "sweep", required=("model", "sweep"), optional=("path",))
        data = _model(body)
        if not isinstance(body["sweep"], dict):
            raise StudioError(400, "sweep: must be an object {kind, grid} or {kind, "
                                   "distributions, n, seed}")
        started = studio.runs.start("sweep", data, body["sweep"],
                                    studio.folder(studio.model_path(body)), studio.library)
        return StudioJSON({"sweep": started.id})

    @api.get("/sweep/{sweep_id}")
    async def poll_sweep(sweep_id: str, wait: float = 0.0):
        job = studio.runs.get(sweep_id, "sweep")
        await _waited(job, wait)
        return Response(job.body(), media_type="application/json")

    @api.post("/sweep/{sweep_id}/cancel")
    def cancel_sweep(sweep_id: str):
        studio.runs.get(sweep_id, "sweep").cancel()
        return StudioJSON({"ok": True})

    @api.post("/linearize")
    async def linearize(body: dict = Depends(_body)):
        _keys(body, "linearize", required=("model",),
              optional=("path", "at", "inputs", "outputs"))
        data = _model(body)
        spec = {k: body.get(k) for k in ("at", "inputs", "outputs")}
        return StudioJSON(await studio.call(work.linearize, data, spec,
                                            studio.folder(studio.model_path(body)),
                                            studio.library, limit=LINEARIZE_LIMIT,
                                            what="linearising the model"))


async def _waited(job, wait, enough=lambda: False):
    """Until ``job`` has ended, ``enough()`` holds or ``wait`` seconds (at most MAX_WAIT) have
    passed: a page polling with a wait hears of the end at once."""
    if not (0.0 <= wait <= MAX_WAIT):
        raise StudioError(400, f"wait: seconds from 0 to {MAX_WAIT:g}, got {wait!r:.40}")
    end = time.monotonic() + wait
    while job.state == "running" and job.cancel_at is None and not enough() and \
            time.monotonic() < end:
        await asyncio.sleep(0.01)


def _rel_or_none(studio, path):
    """A path of the API in canonical form, or None for none."""
    return None if path is None else files.confine(studio.root, path)[1]


def _base(body):
    base = body.get("base")
    if base is not None and (not isinstance(base, str) or len(base) > 200):
        raise StudioError(400, "base: the version the page opened (a string), or null")
    return base


def _open_example(name, studio):
    """An example's text and parsed JSON; one that places subsystem files is given
    self-contained (its definitions inline), since the files stay in the examples folder."""
    path = files.examples().get(name)
    if path is None:
        raise StudioError(404, f"no example {name!r:.80}; GET /api/examples lists them")
    text = files.read_text(path, f"example {name}")
    data = files.parse_model_text(text, f"example {name}")
    if data.get("version") == 2:
        text = dumps(load(path, validate=False))      # folder=None: every definition inline
        data = files.parse_model_text(text, f"example {name}")
    return {"path": None, "text": text, "version": None, "model": data}


async def _save(studio, body):
    """Write a model file: the text the page opened when the model is that text unchanged
    (byte for byte), else kinetwork's canonical text of the model, or, for a model the
    reader refuses (work in progress), the model as it is, with its problems. Written only
    if the file is still the version the page's model was based on, atomically."""
    real, rel = files.confine(studio.root, body["path"])
    data, text = _model(body), body.get("text")
    base = _base(body) if "base" in body else files.UNCHECKED
    if text is not None and not isinstance(text, str):
        raise StudioError(400, "save: text must be a string or null")
    if data.get("format") != FORMAT:
        raise StudioError(400, f"save: the model must be a kinetwork model file's object "
                               f"(\"format\": \"{FORMAT}\")")
    if os.path.isdir(real):
        raise StudioError(400, f"{rel}: a folder, not a model file")
    if not os.path.isdir(os.path.dirname(real)):
        raise StudioError(400, f"{rel}: the folder {os.path.dirname(rel) or '.'} does not exist")
    rendered = await studio.call(work.render, data, text, os.path.dirname(real),
                                 studio.library, what=f"{rel}: writing the model")
    version = await run_in_threadpool(files.write_model, real, rel, rendered["text"], base)
    await run_in_threadpool(files.discard_recovery, studio.root, rel)
    return {"ok": True, "bytes": len(rendered["text"].encode("utf-8")), "text": rendered["text"],
            "version": version, "problems": rendered["problems"]}


# -- requests and refusals ---------------------------------------------------------------------
async def _body(request: Request):
    """The request's JSON object, or a 400 saying what is wrong with it."""
    raw = await request.body()
    if len(raw) > MAX_BODY:
        raise StudioError(400, f"the request is larger than {MAX_BODY // 2**20} MiB")
    try:
        body = json.loads(raw, parse_constant=_no_constant)
    except (ValueError, RecursionError) as exc:
        raise StudioError(400, f"the body is not JSON ({str(exc)[:200]})") from None
    if not isinstance(body, dict):
        raise StudioError(400, "the body must be a JSON object")
    return body


def _no_constant(name):
    raise ValueError(f"{name} is not JSON")


def _keys(body, what, required, optional=()):
    missing = [k for k in required if k not in body]
    if missing:
        raise StudioError(400, f"{what}: required key {missing[0]!r} missing")
    unknown = [k for k in body if k not in required + tuple(optional)]
    if unknown:
        raise StudioError(400, f"{what}: unknown key {unknown[0]!r:.60}; keys are "
                               f"{', '.join(required + tuple(optional))}")


def _model(body):
    data = body["model"]
    if not isinstance(data, dict):
        raise StudioError(400, "model: must be a model file's top-level object {...}")
    return data


def _handlers(app):
    @app.exception_handler(StudioError)
    async def refused(request, exc):
        answer = {"error": exc.message, "problems": exc.problems}
        if isinstance(exc, Conflict):
            answer["conflict"] = {"version": exc.version}
        return StudioJSON(answer, status_code=exc.status)

    @app.exception_handler(HTTPException)
    async def http_error(request, exc):
        return StudioJSON({"error": str(exc.detail), "problems": []},
                          status_code=exc.status_code, headers=exc.headers)

    @app.exception_handler(RequestValidationError)
    async def bad_request(request, exc):
        where = "; ".join(f"{'.'.join(map(str, e.get('loc', ())))}: {e.get('msg')}"
                          for e in exc.errors())
        return StudioJSON({"error": f"bad request: {where}"[:500], "problems": []},
                          status_code=400)

    @app.exception_handler(Exception)
    async def internal(request, exc):
        log.error("internal error on %s %s", request.method, request.url.path, exc_info=exc)
        return StudioJSON({"error": f"internal error ({type(exc).__name__}); the server's "
                                    f"log has the details", "problems": []}, status_code=500)


PLACEHOLDER = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>kinetwork studio</title>
<style>body{font:15px/1.5 system-ui,sans-serif;max-width:40em;margin:3em auto;color:#222}
code{background:#f3f3f3;padding:0 .3em}</style></head>
<body><h1>kinetwork studio</h1>
<p>The server is running, but the studio's page is not built into this installation
(<code>kinetwork/studio/static</code> is missing). Build it from a source checkout with
<code>cd frontend &amp;&amp; npm ci &amp;&amp; npm run build</code>, then reload.</p>
<p>The HTTP API is up meanwhile: <code>/api/palette</code>, <code>/api/files</code>,
<code>/api/examples</code>, <code>/api/open</code>, <code>/api/validate</code>,
<code>/api/save</code>, <code>/api/run</code> (each needs the
token).</p></body></html>
"""
