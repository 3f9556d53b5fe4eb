"""Writing an Animation: the self-contained HTML page, the videos, the command."""

import html
import json
import math
import os
import sys

import numpy as np

from ..errors import ModelError
from ..util import atomic_write
from . import video
from .scene import animation_data

PLAYER = os.path.join(os.path.dirname(os.path.dirname(__file__)), "assets", "player.js")
#: an HTML page holds at most this many times; a denser run is resampled (the player
#: interpolates between samples, so nothing is lost to the eye)
HTML_SAMPLES = 6000


def animate(results, path=None, *, gif=None, mp4=None, fps=None, model=None, height=400):
    """Write the 3-D animation of ``results`` (``res.animate``).

    Parameters
    ----------
    results : kinetwork.Results
    path : str or path-like, optional
        A self-contained HTML page (``.html``): the player and the data inlined, nothing
        fetched from a network. Play, pause, scrub, speed; drag to orbit, wheel to zoom.
    gif, mp4 : str or path-like, optional
        Video files rendered without a browser (MP4 needs ffmpeg: ``pip install
        imageio-ffmpeg``, or one on the PATH).
    fps : float, optional
        Frames per second: of the videos (default 25) and, when given, of the page (by
        default the page keeps the results' grid, at most HTML_SAMPLES times).
    model : kinetwork.Model or kinetwork.System, optional
        What made the results, when they do not say.
    height : int
        Height of the videos in pixels; the width follows the scene's shape.

    Returns
    -------
    dict
        The Animation written (the page's, else the videos'): see the module.

    Raises
    ------
    ModelError
        Nothing to write, a file name of the wrong kind or not writable, no ffmpeg for MP4,
        or no model known.
    """
    wanted = [(path, ".html", "the page"), (gif, ".gif", "gif"), (mp4, ".mp4", "mp4")]
    wanted = [(os.fspath(p), ext, what) for p, ext, what in wanted if p is not None]
    if not wanted:
        raise ModelError("animate: nothing to write: give the path of an HTML page, gif=... "
                         "or mp4=...")
    for p, ext, what in wanted:
        if os.path.isdir(p):
            raise ModelError(f"animate: {what} {p!r:.200} is a folder")
        if not p.lower().endswith(ext) and not (ext == ".html" and p.lower().endswith(".htm")):
            raise ModelError(f"animate: {what} {p!r:.200} must be a {ext} file")
    ffmpeg = video.find_ffmpeg() if mp4 is not None else None
    if mp4 is not None and ffmpeg is None:
        raise ModelError("animate: writing MP4 needs ffmpeg: pip install imageio-ffmpeg (or "
                         "put an ffmpeg on the PATH); a GIF needs nothing more")
    anim = None
    if path is not None:
        anim = animation_data(results, fps=fps, model=model)
        if len(anim["t"]) > HTML_SAMPLES:
            span = anim["t"][-1] - anim["t"][0]
            anim = animation_data(results, fps=(HTML_SAMPLES - 1) / span, model=model)
        page = html_page(anim)
        _write(path, lambda tmp: _write_text(tmp, page))
    if gif is not None or mp4 is not None:
        rate = fps or 25
        clip = animation_data(results, fps=rate, model=model)
        if gif is not None:
            _write(gif, lambda tmp: video.write_gif(clip, tmp, rate, height))
        if mp4 is not None:
            _write(mp4, lambda tmp: video.write_mp4(clip, tmp, rate, height, ffmpeg))
        anim = anim or clip
    return anim


def _write(path, write):
    try:
        atomic_write(path, write)
    except OSError as exc:
        raise ModelError(f"cannot write {path}: {exc.strerror or exc}") from None


def _write_text(path, text):
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


def player_script():
    """The built player (three.js and ``frontend/src/player``), as shipped in the package."""
    try:
        with open(PLAYER, encoding="utf-8") as fh:
            return fh.read()
    except OSError:
        raise ModelError(f"the animation player is missing ({PLAYER}): reinstall kinetwork, or "
                         f"build it (cd frontend && npm ci && npm run build:player)") from None


#: what the page may load: its own inline script and style, nothing from a file or network
CSP = ("default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
       "img-src data: blob:")
STYLE = ("html,body{margin:0;height:100%;overflow:hidden;background:#f4f5f7}"
         "#kinetwork-player{position:fixed;inset:0}")


def html_page(anim):
    """One self-contained HTML page playing ``anim``: no file or network is fetched (its
    Content-Security-Policy allows nothing but its own inline script and style)."""
    data = json.dumps(_rounded(anim), separators=(",", ":"), allow_nan=False)
    # "<" only occurs inside JSON strings, where \u003c reads the same: nothing can close
    # the script element early
    data = data.replace("<", "\\u003c")
    script = player_script().replace("</script", "<\\/script")
    title = html.escape(f"{anim['name']} \u2014 kinetwork animation")
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta http-equiv="Content-Security-Policy" content="{CSP}">
<title>{title}</title>
<style>{STYLE}</style>
</head>
<body>
<div id="kinetwork-player"></div>
<script type="application/json" id="kinetwork-animation">{data}</script>
<script>{script}</script>
</body>
</html>
"""


def _rounded(anim):
    """The Animation with poses to a millionth of the model's size (and of a radian): a
    third of the page's size, and nothing the eye can see."""
    digits = max(0, 6 - math.floor(math.log10(anim["scale"])))
    frames = [dict(f, position=np.round(f["position"], digits).tolist(),
                   quaternion=np.round(f["quaternion"], 6).tolist()) for f in anim["frames"]]
    return dict(anim, frames=frames, t=np.round(anim["t"], 9).tolist())


def cli_animate(args, model):
    """``kinetwork animate MODEL --html out.html [--gif out.gif] [--mp4 out.mp4]``: simulate
    the model (its ``simulation`` block, ``--t-end``) and write its animation."""
    from ..errors import SimulationError
    from ..solver.plan import simulate
    outputs = [("--html", args.html), ("--gif", args.gif), ("--mp4", args.mp4)]
    outputs = [(flag, path) for flag, path in outputs if path]
    if not outputs:
        raise ModelError("animate: nothing to write: give --html FILE.html, --gif FILE.gif "
                         "or --mp4 FILE.mp4")
    for flag, path in outputs:
        if os.path.realpath(path) == os.path.realpath(args.model):
            raise ModelError(f"{flag} {path!r:.200} is the model file itself: choose another "
                             f"path, nothing was run")
        try:
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        except OSError as exc:
            raise ModelError(f"cannot write {path}: {exc.strerror or exc}") from None
    code = 0
    try:
        results = simulate(model, t_end=args.t_end)
    except SimulationError as exc:
        print(f"kinetwork: error: {exc}", file=sys.stderr)
        if exc.results is None or len(exc.results.t) < 2:
            return 3
        results, code = exc.results, 3
    anim = animate(results, args.html, gif=args.gif, mp4=args.mp4, fps=args.fps,
                   model=model)
    for flag, path in outputs:
        print(f"wrote {flag[2:]} {path} ({os.path.getsize(path)} bytes, "
              f"{len(anim['t'])} frames over {anim['t'][-1] - anim['t'][0]:g} s)")
    return code

