"""The studio's HTTP server: the API of ``API.md`` over kinetwork, and the built front end.

``create_app(root, token)`` gives an ASGI app (FastAPI). Every ``/api`` route checks the
session token; files are read and written only inside ``root``; a model is checked by the
checker of ``kn.load`` and written by kinetwork's writer; runs go in worker threads. Answers
are JSON, a refusal ``{"error", "problems"}`` with 400, 403, 404 or 409, never a traceback.
"""

import contextlib
import json
import logging
import os
import pathlib
import secrets

from fastapi import APIRouter, Depends, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response
from starlette.exceptions import HTTPException

from ..errors import ModelError
from ..graph.io import FORMAT, MAX_FILE_SIZE, load, loads
from ..graph.writer import dumps
from ..schema import schema
from ..util import atomic_write
from . import checks, files
from .files import StudioError
from .runs import Runs, check_settings, encode

log = logging.getLogger("kinetwork.studio")

STATIC = pathlib.Path(__file__).resolve().parent / "static"
TOKEN_HEADER = "X-Kinetwork-Token"
#: the largest request body: a model file's limit, and room for its JSON around it
MAX_BODY = 2 * MAX_FILE_SIZE


class StudioJSON(JSONResponse):
    """JSON as the page reads it: compact, numpy values as lists, NaN and infinities null
    (JSON has none, and a model file or partial results may hold them)."""

    def render(self, content):
        return encode(content)


def create_app(root, token, library=None, model=None):
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

    @contextlib.asynccontextmanager
    async def lifespan(app):
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
        index = STATIC / "index.html"
        if index.is_file():
            return FileResponse(index, headers={"Cache-Control": "no-store"})
        return HTMLResponse(PLACEHOLDER)

    @app.get("/assets/{name:path}", include_in_schema=False)
    def asset(name: str):
        # no token: the page's scripts and styles are the same for everyone; only the built
        # files are served, and nothing the path could reach outside their folder
        folder = os.path.realpath(STATIC / "assets")
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

    def check_token(self, request: Request):
        given = request.headers.get(TOKEN_HEADER) or request.query_params.get("token") or ""
        if not secrets.compare_digest(given.encode("utf-8", "replace"),
                                      self.token.encode("utf-8")):
            raise StudioError(403, "missing or wrong token: open the address that "
                                   "`kinetwork studio` printed")

    def context(self, real_path=None):
        return checks.context(checks.folder_of(self.root, real_path), self.library)

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
        text = files.read_text(real, rel)
        return StudioJSON({"path": rel, "text": text,
                           "model": files.parse_model_text(text, rel)})

    @api.post("/validate")
    def validate(body: dict = Depends(_body)):
        _keys(body, "validate", required=("model",), optional=("path",))
        data = _model(body)
        return StudioJSON(checks.validate(data, studio.context(studio.model_path(body))))

    @api.post("/save")
    def save(body: dict = Depends(_body)):
        _keys(body, "save", required=("path", "model"), optional=("text",))
        return StudioJSON(_save(studio, body))

    @api.post("/layout")
    def layout(body: dict = Depends(_body)):
        _keys(body, "layout", required=("model",), optional=("path",))
        data = _model(body)
        try:
            model = checks.build(data, studio.context(studio.model_path(body)), validate=False)
        except ModelError as exc:
            raise StudioError(400, "the model cannot be read", checks.problems_of(exc))
        return StudioJSON({"layout": checks.layout(model)})

    @api.post("/run")
    def run(body: dict = Depends(_body)):
        _keys(body, "run", required=("model",), optional=("settings", "path"))
        data = _model(body)
        settings = check_settings(body.get("settings"))
        started = studio.runs.start(data, settings, studio.context(studio.model_path(body)))
        return StudioJSON({"run": started.id})

    @api.get("/run/{run_id}")
    def poll(run_id: str):
        return Response(studio.runs.get(run_id).body(), media_type="application/json")

    @api.post("/run/{run_id}/cancel")
    def cancel(run_id: str):
        studio.runs.get(run_id).cancel.set()
        return StudioJSON({"ok": True})


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
    return {"path": None, "text": text, "model": data}


def _save(studio, body):
    """Write a model file: the text the page opened when the model is that text unchanged
    (byte for byte), else kinetwork's canonical text of the model. Either way the text is
    read back as ``kn.load`` would (without the wiring checks, so work in progress saves)
    before the old file is replaced, atomically."""
    real, rel = files.confine(studio.root, body["path"])
    data, text = _model(body), body.get("text")
    if text is not None and not isinstance(text, str):
        raise StudioError(400, "save: text must be a string or null")
    if os.path.isdir(real):
        raise StudioError(400, f"{rel}: a folder, not a model file")
    if not os.path.isdir(os.path.dirname(real)):
        raise StudioError(400, f"{rel}: the folder {os.path.dirname(rel) or '.'} does not exist")
    if os.path.exists(real):
        _check_overwrite(real, rel)
    ctx = studio.context(real)
    unchanged = text is not None and _same(_json_or_none(text), data)
    try:
        if unchanged:
            loads(text, validate=False, library=studio.library, folder=os.path.dirname(real))
            written = text

            def write(tmp):
                with open(tmp, "wb") as fh:
                    fh.write(written.encode("utf-8"))
            atomic_write(real, write)
        else:
            model = checks.build(data, ctx, validate=False)
            model.save(real)
            written = files.read_text(real, rel)
    except ModelError as exc:
        raise StudioError(400, f"{rel}: not saved: the model cannot be written as a file",
                          checks.problems_of(exc)) from None
    except OSError as exc:
        raise StudioError(400, f"{rel}: not saved: {exc.strerror or exc}") from None
    return {"ok": True, "bytes": len(written.encode("utf-8")), "text": written}


def _check_overwrite(real, rel):
    """A file already there is replaced only when it is a kinetwork model file."""
    try:
        data = json.loads(files.read_text(real, rel))
    except (StudioError, ValueError, RecursionError):
        data = None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise StudioError(409, f"{rel}: exists and is not a kinetwork model file; not "
                               f"overwritten (save under another name)")


def _same(a, b):
    """JSON values equal as the page sees them: 1 and 1.0 alike (JavaScript has one number
    type), but true and 1 not, nor "1" and 1."""
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


def _json_or_none(text):
    try:
        return json.loads(text)
    except (ValueError, RecursionError):
        return None


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
        return StudioJSON({"error": exc.message, "problems": exc.problems},
                          status_code=exc.status)

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
<code>/api/save</code>, <code>/api/layout</code>, <code>/api/run</code> (each needs the
token).</p></body></html>
"""
