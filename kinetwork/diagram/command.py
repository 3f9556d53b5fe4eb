"""``kinetwork diagram MODEL -o out.svg``: the command that writes a model's diagram."""

import os

from ..errors import ModelError
from ..outputs import check, model_files, write
from .drawing import svg


def cli_diagram(args, model):
    """``kinetwork diagram MODEL -o out.svg``: write the diagram; the exit code."""
    path = args.out
    if not str(path).lower().endswith(".svg"):
        raise ModelError(f"-o {path}: a diagram is written as SVG; name a .svg file")
    reads, force = model_files(model), getattr(args, "force", False)
    check(path, "svg", what="-o", reads=reads, force=force)       # before drawing anything
    text = svg(model)

    def fill(tmp):
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        write(path, fill, "svg", what="-o", reads=reads, force=force)
    except OSError as exc:
        raise ModelError(f"cannot write {path}: {exc.strerror or exc}") from None
    print(f"wrote the diagram of {model.name} ({len(model.components)} components, "
          f"{len(model.connections)} connections) to {path}")
    return 0
