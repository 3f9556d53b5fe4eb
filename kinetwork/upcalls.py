"""The four calls that go up the layers, in one table a reader can follow.

Layers only look down (``tests/test_layers.py``): a ``Model`` (graph) may not import the
equations that compile it, nor ``Results`` (solver) the plot that draws them. Yet
``model.compile()``, ``model._repr_svg_()``, ``res.plot()`` and ``res.animate()`` are where
users look for that work. Each of those methods calls ``upcall(name)``, which imports the
module this table names and returns its function: the same function whatever was imported
before, in any process, with nothing installed at import time. To follow ``Model.compile``
to the equations, read ``UPCALLS["compile"]``.
"""

import importlib

#: name -> (module, function): what each method of a lower layer hands its work to
UPCALLS = {
    # Model.compile -> compile(model, loops=, baumgarte_rate=): the System, loaded when
    # kept on disk, else built (and validated) then kept
    "compile": ("kinetwork.equations.stored", "compile"),
    # Model._repr_svg_ -> svg(model): the wiring diagram Jupyter shows
    "diagram": ("kinetwork.diagram", "svg"),
    # Results.plot, Results._repr_html_ -> plot_results(results, *names, **options)
    "plot": ("kinetwork.plot", "plot_results"),
    # Results.animate -> animate(results, path, **options)
    "animate": ("kinetwork.animation", "animate"),
}


def upcall(name):
    """The function that does the work of upcall ``name`` (a key of ``UPCALLS``)."""
    module, function = UPCALLS[name]
    return getattr(importlib.import_module(module), function)
