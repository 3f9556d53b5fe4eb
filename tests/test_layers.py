"""The layers of kinetwork only look down, and no module imports itself back.

Every module is read with ``ast`` (nothing is imported): each import, at any depth (inside
functions too), relative or absolute, is resolved to the kinetwork module it names. Layers,
lowest first (the package docstring's list): the helpers ``errors``, ``util``, ``expr``,
``units``, ``spatial``, ``upcalls``; ``components``; ``graph``; ``equations``; ``solver``; the faces
``plot``, ``schema``, ``symbolic``, ``cli`` (and ``kinetwork/__init__.py``, which gathers
them all). A module of a sub-package is in its package's layer. A module may import from its
own layer and those below it; the imports must not form a cycle, within a layer either.
"""

import ast
import os
import pathlib

import networkx as nx
import pytest

import kinetwork

PACKAGE = pathlib.Path(kinetwork.__file__).resolve().parent
LAYERS = [("errors", "util", "expr", "units", "spatial", "upcalls"), ("components",), ("graph",),
          ("equations",), ("solver", "simulation"),
          ("plot", "plotlayout", "plotworker", "quickplot", "schema", "symbolic", "animation",
           "diagram", "urdf", "examples", "studio", "analysis", "fmu", "cli", "__main__", "")]
RANK = {name: rank for rank, names in enumerate(LAYERS) for name in names}


def module_name(path):
    """``kinetwork.graph.model`` of ``.../kinetwork/graph/model.py`` (``__init__`` files name
    their package)."""
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def layer(module):
    """The layer of a module: the first name below ``kinetwork`` ("" for the package)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def imports(module):
    """(line, kinetwork module) of every import in ``module``, at any depth."""
    path = MODULES[module]
    tree = ast.parse(path.read_text(), filename=str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    # imports for annotations only (``if TYPE_CHECKING:``) never run: a Model.compile may
    # say it returns a System without the graph layer importing the equations
    typing_only = {id(inner) for node in ast.walk(tree) if isinstance(node, ast.If)
                   and (getattr(node.test, "id", None) == "TYPE_CHECKING"
                        or getattr(node.test, "attr", None) == "TYPE_CHECKING")
                   for stmt in node.body for inner in ast.walk(stmt)}
    found = []
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for alias in node.names:
                # ``from . import plot``: the module kinetwork.plot, else a name of the package
                sub = f"{target}.{alias.name}"
                found.append((node.lineno, sub if sub in MODULES else target))
    out = []
    for line, name in found:
        while name and name not in MODULES and "." in name:
            name = name.rpartition(".")[0]          # ``import kinetwork.graph.model.x``
        if name in MODULES:
            out.append((line, name))
    return out


def test_every_module_is_in_a_layer():
    unplaced = sorted({layer(m) for m in MODULES} - set(RANK))
    assert not unplaced, f"modules in no layer: {unplaced}"
    assert len(MODULES) > 30          # the walk found the package, not an empty folder


def test_imports_only_look_down():
    upward = [f"{os.path.relpath(MODULES[m], PACKAGE.parent)}:{line}: {m} "
              f"({layer(m) or 'kinetwork'}) imports {target} ({layer(target) or 'kinetwork'})"
              for m in MODULES for line, target in imports(m)
              if RANK[layer(target)] > RANK[layer(m)]]
    assert not upward, "imports from a higher layer:\n" + "\n".join(upward)


def test_no_import_cycles():
    graph = nx.DiGraph()
    graph.add_nodes_from(MODULES)
    for m in MODULES:
        graph.add_edges_from((m, target) for _, target in imports(m) if target != m)
    cycles = sorted(" -> ".join(c + [c[0]]) for c in nx.simple_cycles(graph))
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


@pytest.mark.parametrize("source, module, expected", [
    ("from ..errors import ModelError", "kinetwork.graph.model", "kinetwork.errors"),
    ("from . import plot as _plot", "kinetwork", "kinetwork.plot"),
    ("from .base import Component", "kinetwork.components.multibody",
     "kinetwork.components.base"),
    ("def f():\n    from .topology import analyze", "kinetwork.graph.model",
     "kinetwork.graph.topology"),
    ("import kinetwork.solver.jit", "kinetwork.cli", "kinetwork.solver.jit"),
    ("from kinetwork.components import multibody", "kinetwork.cli",
     "kinetwork.components.multibody"),
    ("from kinetwork import Model", "kinetwork.cli", "kinetwork"),
])
def test_imports_are_resolved_to_modules(source, module, expected, monkeypatch, tmp_path):
    """The resolution itself, on small sources: relative, absolute, nested, of a name."""
    fake = tmp_path / MODULES[module].name
    fake.write_text(source + "\n")
    monkeypatch.setitem(MODULES, module, fake)
    assert [target for _, target in imports(module)] == [expected]


def test_the_two_plot_renderers_share_one_layout_module():
    """plot.py (matplotlib) and quickplot.py (Pillow) both draw the layout plotlayout.py
    decides (panels, ticks, labels, margins); neither imports the other."""
    for module, other in (("kinetwork.plot", "kinetwork.quickplot"),
                          ("kinetwork.quickplot", "kinetwork.plot")):
        targets = {target for _, target in imports(module)}
        assert other not in targets and "kinetwork.plotlayout" in targets


def test_components_are_free_of_casadi_at_import():
    """A component declares; it builds CasADi expressions only when the equations ask (its
    methods import CasADi): importing every library, building components and reading a model
    file without validating it load no CasADi (``components/quantities.py`` says so)."""
    import subprocess
    import sys
    seed = PACKAGE.parent / "models" / "double_pendulum.json"
    program = ("import sys, kinetwork as kn, kinetwork.components, kinetwork.spatial\n"
               "kn.multibody.Revolute('j', n=[0, 0, 1]); kn.rotational.IdealGear('g', ratio=2)\n"
               f"kn.load({str(seed)!r}, validate=False)\n"
               "print('casadi' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "False"
