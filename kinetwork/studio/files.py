"""The studio's files: paths confined to its root, the model files under it, the examples.

Every path the browser sends is relative to the root, the folder the studio was started in.
A path that would leave it (``..``, an absolute path, a URL, a symbolic link pointing out) is
refused before the disk is touched, so a page (or anything else holding the token) reads and
writes model files inside that folder and nowhere else.
"""

import json
import os
import re

from ..graph.io import MAX_FILE_SIZE

#: model files are JSON: the studio opens and writes nothing else
SUFFIX = ".json"
#: how deep ``files`` looks below the root, and how many files it lists at most
MAX_DEPTH, MAX_FILES = 5, 5000
#: folders ``files`` does not look into (besides hidden ones: .git, .venv, ...)
SKIPPED = {"node_modules", "__pycache__", "site-packages"}


class StudioError(Exception):
    """A refusal answered as ``{"error": message, "problems": [...]}`` with ``status``."""

    def __init__(self, status, message, problems=()):
        super().__init__(message)
        self.status, self.message, self.problems = status, message, list(problems)


def confine(root, rel, what="path"):
    """The real absolute path of ``rel`` inside ``root``, and ``rel`` in canonical form
    (``models/a.json``).

    Raises
    ------
    StudioError
        400: not a relative path of a ``.json`` file inside the root.
    """
    if not isinstance(rel, str) or not rel.strip():
        raise StudioError(400, f"{what}: must be a path relative to the studio's folder, got "
                               f"{_shown(rel)}")
    if "\x00" in rel or len(rel) > 1024:
        raise StudioError(400, f"{what}: not a usable file name")
    if rel.startswith(("/", "\\", "~")) or os.path.isabs(rel) or "://" in rel or \
            re.match(r"[A-Za-z]:", rel):
        raise StudioError(400, f"{what} {_shown(rel)}: must be relative to the studio's "
                               f"folder (no absolute path, no URL)")
    parts = [p for p in re.split(r"[/\\]", rel) if p not in ("", ".")]
    if ".." in parts:
        raise StudioError(400, f"{what} {_shown(rel)}: '..' would leave the studio's folder")
    if not parts or not parts[-1].endswith(SUFFIX) or parts[-1] == SUFFIX:
        raise StudioError(400, f"{what} {_shown(rel)}: a model file's name ends in {SUFFIX}")
    real = os.path.realpath(os.path.join(root, *parts))
    if os.path.commonpath([real, root]) != root:
        raise StudioError(400, f"{what} {_shown(rel)}: a symbolic link leads out of the "
                               f"studio's folder")
    if not real.endswith(SUFFIX):
        raise StudioError(400, f"{what} {_shown(rel)}: a symbolic link to a file not ending "
                               f"in {SUFFIX}")
    return real, "/".join(parts)


def list_files(root):
    """The ``.json`` files under ``root``, at most MAX_DEPTH folders down, as sorted relative
    paths; hidden folders, node_modules and links leading out are left aside."""
    found = []
    for folder, dirs, names in os.walk(root):
        depth = 0 if folder == root else os.path.relpath(folder, root).count(os.sep) + 1
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in SKIPPED
                         and depth + 1 < MAX_DEPTH)
        for name in names:
            path = os.path.join(folder, name)
            if name.endswith(SUFFIX) and not name.startswith(".") and os.path.isfile(path) \
                    and os.path.commonpath([os.path.realpath(path), root]) == root:
                found.append(os.path.relpath(path, root).replace(os.sep, "/"))
                if len(found) >= MAX_FILES:
                    return sorted(found)
    return sorted(found)


def read_text(path, what):
    """A file's text (UTF-8, a BOM tolerated as ``kn.load`` does), refused past
    MAX_FILE_SIZE."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_FILE_SIZE + 1)
    except FileNotFoundError:
        raise StudioError(404, f"{what}: no such file") from None
    except IsADirectoryError:
        raise StudioError(400, f"{what}: a folder, not a model file") from None
    except OSError as exc:
        raise StudioError(400, f"{what}: cannot read the file ({exc.strerror or exc})") from None
    if len(raw) > MAX_FILE_SIZE:
        raise StudioError(400, f"{what}: larger than {MAX_FILE_SIZE // 2**20} MiB, too large "
                               f"for a model file")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise StudioError(400, f"{what}: not UTF-8 text (byte {exc.start})") from None


def parse_model_text(text, what):
    """The top-level object of a model file's text, as written (nothing checked but JSON)."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise StudioError(400, f"{what}: line {exc.lineno} column {exc.colno}: invalid JSON: "
                               f"{exc.msg}") from None
    except (ValueError, RecursionError) as exc:
        raise StudioError(400, f"{what}: invalid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise StudioError(400, f"{what}: not a model file (its JSON is not an object)")
    return data


# -- the examples -----------------------------------------------------------------------------
def examples():
    """Example name (its path in the folder, without ``.json``: ``robot/arm_axes``) -> file;
    the package's own list (``kinetwork.examples``)."""
    from .. import examples as shipped
    return shipped.names()


def _shown(value):
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."
