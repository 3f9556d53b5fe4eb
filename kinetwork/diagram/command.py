"""``kinetwork diagram MODEL -o out.svg``: the command that writes a model's diagram."""

import os

from ..errors import ModelError
from ..util import atomic_write
from .drawing import svg


def cli_diagram(args, model):
    """``kinetwork diagram MODEL -o out.svg``: write the diagram; the exit code."""
    path = args.out
    if not str(path).lower().endswith(".svg"):
        raise ModelError(f"-o {path}: a diagram is written as SVG; name a .svg file")
    if os.path.isdir(path):
        raise ModelError(f"cannot write {path}: it is a folder")
    text = svg(model)

    def write(tmp):
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        atomic_write(path, write)
    except OSError as exc:
        raise ModelError(f"cannot write {path}: {exc.strerror or exc}") from None
    print(f"wrote the diagram of {model.name} ({len(model.components)} components, "
          f"{len(model.connections)} connections) to {path}")
    return 0
