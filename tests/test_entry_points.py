"""Every public entry point works as the first call of a fresh interpreter.

Nothing is installed at import time (``kinetwork.upcalls``): a method of a lower layer that
hands work up (``Model.compile``, ``Model._repr_svg_``, ``Results.plot``,
``Results.animate``) finds its function itself. Each case runs in its own interpreter, so no
import made by another test (or by pytest's collection) can hide a missing one; the modules
are reached both through ``kinetwork``'s lazy names and directly, below the package's
``__init__``.
"""

import importlib
import os
import subprocess
import sys

import pytest

from kinetwork.upcalls import UPCALLS, upcall
from test_layers import RANK, layer

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SEED = os.path.join(ROOT, "models", "double_pendulum.json")

#: name -> the program; it prints "ok" at its end
CASES = {
    "load.compile": """
import kinetwork
system = kinetwork.load(SEED).compile()
assert system.state_names == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
""",
    "graph.io.load.compile": """
from kinetwork.graph.io import load
assert load(SEED).compile().n_states == 4
""",
    "Model.compile": """
from kinetwork.graph.model import Model
from kinetwork.components.multibody import Ground, Revolute, RigidBody
m = Model("m")
m.add(Ground("g")); m.add(Revolute("j")); m.add(RigidBody("b", mass=1.0, r_cm=[1, 0, 0]))
m.connect("g.frame", "j.frame_a"); m.connect("j.frame_b", "b.frame_a")
assert m.compile().state_names == ["j.q", "j.qd"]
""",
    "Model._repr_svg_": """
from kinetwork.graph.io import load
assert load(SEED)._repr_svg_().startswith("<svg")
""",
    "kn.Model._repr_svg_": """
import kinetwork as kn
assert kn.load(SEED)._repr_svg_().startswith("<svg")
""",
    "simulate": """
import kinetwork as kn
res = kn.simulate(SEED_MODEL(), t_end=0.1, n_points=11)
assert res["probe1.angle"].shape == (11,)
""",
    "Results.plot": """
from kinetwork.graph.io import load
from kinetwork.solver.plan import simulate
res = simulate(load(SEED), t_end=0.1, n_points=11)
assert len(res.plot().axes) >= 4
""",
    "Results._repr_html_": """
from kinetwork.graph.io import load
from kinetwork.solver.plan import simulate
assert "<svg" in simulate(load(SEED), t_end=0.1, n_points=11)._repr_html_()
""",
    "Results.animate": """
import os, tempfile
from kinetwork.graph.io import load
from kinetwork.solver.plan import simulate
res = simulate(load(SEED), t_end=0.1, n_points=11)
path = os.path.join(tempfile.mkdtemp(), "a.html")
res.animate(path)
assert os.path.getsize(path) > 1000
""",
    "sweep": """
import kinetwork as kn
ds = kn.sweep(SEED_MODEL(), {"c": [1.0, 2.0]}, t_end=0.1, n_points=3)
assert ds.sizes["c"] == 2
""",
    "linearize": """
import kinetwork as kn
lin = kn.linearize(SEED_MODEL(), outputs=["probe1.angle"])
assert lin.A.shape == (4, 4)
""",
    "sensitivity": """
import kinetwork as kn
sens = kn.sensitivity(SEED_MODEL(), ["c"], t_end=0.1, n_points=3, outputs=["probe1.angle"])
assert sens.S.shape == (3, 1, 1)
""",
    "modes": """
import kinetwork as kn
assert len(kn.modes(SEED_MODEL())) == 2
""",
    "cli run": """
import os, subprocess, sys
done = subprocess.run([sys.executable, "-m", "kinetwork", "run", SEED, "--t-end", "0.1",
                       "--n-points", "3", "--out", "out.csv", "--quiet"],
                      capture_output=True, text=True)
assert done.returncode == 0, done.stderr
assert open("out.csv").readline().startswith("t,")
""",
    "plot module": """
import kinetwork as kn
res = kn.simulate(SEED_MODEL(), t_end=0.1, n_points=11)
assert kn.plot(res) is not None
""",
}

PRELUDE = f"""
SEED = {SEED!r}
def SEED_MODEL():
    import kinetwork
    return kinetwork.load(SEED)
"""


@pytest.mark.parametrize("case", CASES)
def test_an_entry_point_works_as_the_first_call(case, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONWARNINGS="error",
               KINETWORK_CACHE=str(tmp_path / "cache"))
    program = PRELUDE + CASES[case] + "\nprint('ok')\n"
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          cwd=tmp_path, env=env)
    assert done.returncode == 0 and done.stdout.strip().endswith("ok"), done.stderr[-3000:]


@pytest.mark.parametrize("name", UPCALLS)
def test_each_upcall_names_a_function_of_a_higher_layer(name):
    module, function = UPCALLS[name]
    assert callable(upcall(name))
    assert upcall(name) is getattr(importlib.import_module(module), function)
    # it goes up: from graph (compile, diagram) or solver (plot, animate) to a layer above
    caller = {"compile": "graph", "diagram": "graph", "plot": "solver", "animate": "solver"}
    assert RANK[layer(module)] > RANK[caller[name]]
