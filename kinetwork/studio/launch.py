"""``kinetwork studio``: start the server on 127.0.0.1 with a fresh token, open the browser.

The root, the only folder the studio reads and writes, is the current directory; a model
given on the command line that lies outside it makes its own folder the root instead, so it
can be opened and saved. A model name that is no file but an example opens the example.
"""

import os
import secrets
import socket
import sys
import urllib.parse
import webbrowser

from ..errors import ModelError

HOST = "127.0.0.1"


def cli_studio(args):
    """Run the studio until Ctrl-C; returns the exit code (0).

    ``args``: ``model`` (a file, or an example's name, or None), ``port`` (None: a free
    one), ``no_browser`` and ``library`` (folders), as ``kinetwork studio`` parses them.
    """
    try:
        import uvicorn

        from .server import create_app
    except ImportError as exc:
        raise ModelError(f"the studio needs FastAPI and uvicorn ({exc.name} is not "
                         f"installed): pip install 'kinetwork[studio]'") from None
    root, query = _root_and_query(getattr(args, "model", None))
    token = secrets.token_urlsafe(32)
    sock = _listen(getattr(args, "port", None))
    port = sock.getsockname()[1]
    app = create_app(root, token, library=getattr(args, "library", None) or None,
                     model=query.get("open"))
    url = f"http://{HOST}:{port}/?" + urllib.parse.urlencode({"token": token, **query})
    print(f"kinetwork studio: files in {root}\n  {url}\n(Ctrl-C stops it)", flush=True)
    if not getattr(args, "no_browser", False):
        _open_browser(url)
    # Ctrl-C stops at once: requests still open get half a second (the work they wait on is
    # in child processes, ended with them), not for ever
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="on",
                                           timeout_graceful_shutdown=0.5))
    try:
        server.run(sockets=[sock])
    except KeyboardInterrupt:       # uvicorn shuts down, then raises the signal it caught
        pass
    finally:
        sock.close()
    return 0


def _open_browser(url):
    """Open the page, unless this is a Linux machine without a display: there Python's
    ``webbrowser`` would start a text browser in this terminal and wait for it."""
    headless = sys.platform.startswith("linux") and not any(
        os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY", "BROWSER"))
    if headless or not webbrowser.open(url):
        print("(no browser here: open the address above in one)", flush=True)


def _root_and_query(model):
    """The root folder, and what the page's URL asks it to open (``open`` or ``example``)."""
    root = os.path.realpath(os.getcwd())
    if model is None:
        return root, {}
    if os.path.isfile(model):
        path = os.path.realpath(model)
        if os.path.commonpath([path, root]) != root:
            root = os.path.dirname(path)
        return root, {"open": os.path.relpath(path, root).replace(os.sep, "/")}
    from .files import examples
    if model in examples():
        return root, {"example": model}
    raise ModelError(f"{model}: no such file, nor an example of that name (examples: "
                     f"{', '.join(sorted(examples())) or 'none installed'})")


def _listen(port):
    """A listening socket on HOST: ``port``, or a free one the system picks (held open
    from here on, so nothing can take it before the server starts)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((HOST, port or 0))
    except OSError as exc:
        sock.close()
        raise ModelError(f"cannot listen on {HOST}:{port}: {exc.strerror or exc}") from None
    sock.listen(128)
    return sock
