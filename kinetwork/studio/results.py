"""Results as the page reads them: the time grid, every probe signal with its descriptor, the
3-D animation (or why there is none), and where a partial run stopped; encoded as compact
JSON with non-finite numbers as null."""

import contextlib
import gc
import json
import logging
import math

import numpy as np

from .checks import plain

try:        # the studio's extras: the same JSON written ten times as fast as json's
    import orjson
except ImportError:             # pragma: no cover -- json's way below
    orjson = None

log = logging.getLogger("kinetwork.studio")

#: the most time samples of a run's 3-D animation: a denser run is resampled (the viewer
#: interpolates between samples), or the poses of a large scene would be tens of MB of JSON
MAX_FRAMES = 1000
#: the poses' rounding, relative to the scene's size (animation_data): 1e-7 of it is far below
#: a pixel, and halves the JSON and its writing (EngineV6: 11 MB, 0.6 s of CPU a run before)
RESOLUTION = 1e-7
#: what the 3-D view says of a model without multibody parts
NO_SCENE = "This model has no multibody parts (it is 1-D only): there is nothing to show in 3-D."


def results_json(res, model=None, with_animation=True):
    """Results as the page reads them: the time grid and every probe signal, values nested
    with n_points first, non-finite values null; and the 3-D animation when it can be made,
    else ``animation_note`` says why (both None without ``with_animation``: see
    ``animation_json``). Numbers are numpy arrays, for ``encode`` (which writes them as nested
    lists, non-finite values as null)."""
    with paused_collection():
        anim, note = animation(res, model) if with_animation else (None, None)
        return _results_json(res, anim, note)


def animation_json(res, model=None):
    """``{"animation", "animation_note"}`` of ``results_json``, made apart: what
    ``GET /api/run/{id}/animation`` answers after the plots' results went ahead."""
    with paused_collection():
        anim, note = animation(res, model)
        return {"animation": anim, "animation_note": note}


def _results_json(res, anim, note):
    return {
        "t": np.asarray(res.t, dtype=float),
        "signals": [{"name": name, "unit": sig.unit, "shape": list(sig.shape),
                     "probe": sig.probe, "quantity": sig.quantity, "port": sig.target,
                     "values": np.ascontiguousarray(res[name], dtype=float)}
                    for name, sig in res.signals.items()],
        "animation": anim,
        "animation_note": note,
        "partial": plain(res.partial),
    }


def has_scene(model):
    """Whether a model has anything the 3-D view draws: a multibody frame."""
    if model is None:
        return True
    flat = model.flat() if hasattr(model, "flat") else model
    return any(port.domain == "frame" for comp in flat.components.values()
               for port in type(comp).ports.values())


def animation(res, model=None):
    """``(animation_data(res), None)`` for the results of ``model``, or ``(None, why)``
    when the scene has nothing to show or cannot be made."""
    if not has_scene(model):
        return None, NO_SCENE
    try:
        from ..animation import animation_data
    except ImportError:
        return None, "The 3-D view is not installed with this kinetwork."
    try:
        n, span = len(res.t), float(res.t[-1] - res.t[0]) if len(res.t) else 0.0
        fps = (MAX_FRAMES - 1) / span if n > MAX_FRAMES and span > 0 else None
        return animation_data(res, fps=fps, model=model, resolution=RESOLUTION,
                              arrays=True), None
    except Exception as exc:      # noqa: BLE001 -- the plots are worth showing without it
        log.warning("no 3-D view for these results: %s: %s", type(exc).__name__, exc)
        return None, f"The 3-D view could not be made for this model ({type(exc).__name__})."


def encode(content):
    """JSON bytes as the page reads them: compact, numpy values as lists, NaN and infinities
    null (JSON has none, and a model file or partial results may hold them).

    By orjson when it is installed (EngineV6's answer, 6 MB of numbers: 0.011 s of CPU
    against json's 0.13), which writes the same values (floats as their shortest round trip,
    ``1e-7`` for json's ``1e-07``); by json otherwise, or for what orjson refuses (an integer
    past 64 bits)."""
    with paused_collection():
        if orjson is not None:
            try:
                return orjson.dumps(content, default=_numpy, option=_ORJSON)
            except TypeError:
                pass
        try:
            text = json.dumps(content, allow_nan=False, separators=(",", ":"), default=_numpy)
        except ValueError:
            text = json.dumps(_finite(content), allow_nan=False, separators=(",", ":"),
                              default=_numpy)
        return text.encode("utf-8")


@contextlib.contextmanager
def paused_collection():
    """Python's cyclic garbage collector paused within: results are hundreds of thousands of
    new lists and floats and no cycles, and each collection their count sets off scans the
    whole heap (EngineV6's answer: 0.15 of its 0.46 s of CPU went to 297 collections)."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


#: numpy arrays and scalars as lists and numbers, keys that are not strings as strings (as
#: json writes them)
_ORJSON = 0 if orjson is None else orjson.OPT_SERIALIZE_NUMPY | orjson.OPT_NON_STR_KEYS


def _numpy(value):
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON")


def _finite(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value
