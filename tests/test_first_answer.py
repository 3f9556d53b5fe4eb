"""The quick first answer of ``kinetwork run`` (issue 18, item 4): what the command imports,
its drawing process, and the plot files' measured margins.

Imports are checked in a fresh interpreter (deterministic; no timing is asserted here, the
timings are bench/study_first_answer.py's).
"""

import json
import os
import subprocess
import sys
import textwrap

import matplotlib
import numpy as np
import pytest
from conftest import double_pendulum

import kinetwork as kn
from kinetwork import plotworker
from kinetwork.plot import FORMATS, plot_results

matplotlib.use("Agg")
from matplotlib.backend_bases import FigureCanvasBase  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402

ENV = dict(os.environ, KINETWORK_JIT="0")       # no C compiler in the way


def python(code, cwd):
    """Run ``code`` in a fresh interpreter; (return code, stdout, stderr)."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, env=ENV,
                          capture_output=True, text=True, timeout=300)
    return done.returncode, done.stdout, done.stderr


@pytest.fixture(scope="module")
def seed_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("seed") / "seed.json"
    double_pendulum().save(path)
    return path


def test_the_command_line_imports_what_a_run_needs_and_nothing_else(seed_file, tmp_path):
    """Importing the CLI loads no numpy (its drawing process forks before that); a run
    without --plot loads neither matplotlib nor scipy nor the animation and diagram faces."""
    code, out, err = python(f"""
        import json, sys
        from kinetwork import cli
        at_start = sorted(m for m in ("numpy", "casadi", "networkx") if m in sys.modules)
        code = cli.main(["run", {str(seed_file)!r}, "--out", "r.csv", "--quiet"])
        loaded = sorted(m for m in ("matplotlib", "scipy", "sympy", "pandas", "PIL",
                                    "kinetwork.animation", "kinetwork.diagram")
                        if m in sys.modules)
        print(json.dumps([at_start, code, loaded]))
    """, tmp_path)
    assert code == 0, err
    at_start, run_code, loaded = json.loads(out.splitlines()[-1])
    assert at_start == [] and run_code == 0 and loaded == []
    assert (tmp_path / "r.csv").exists()


def test_run_with_plot_draws_in_its_own_process(seed_file, tmp_path):
    """The command line's --plot never imports matplotlib in the command's process: a PNG is
    drawn there with Pillow, another format by the forked process; also for a partial run; the
    refusals reach the user as before; a drawing process that died leaves the drawing to the
    parent."""
    blowup = double_pendulum()
    blowup.add(kn.rotational.Torque("blowup", tau="1/(1-t)**3"))
    blowup.connect("blowup.flange", "shoulder.axis")
    blowup.save(tmp_path / "blowup.json")
    _, out, err = python(f"""
        import json, os, signal, sys
        from kinetwork import cli, plotworker

        def run(*argv):
            sys.argv = ["kinetwork", "run", *argv]
            return cli.main()

        codes = [run({str(seed_file)!r}, "--out", "a.csv", "--plot", "a.png", "--t-end", "1"),
                 run("blowup.json", "--out", "b.csv", "--plot", "b.png"),
                 run({str(seed_file)!r}, "--plot", "c.png", "--plot-signals", "probe9"),
                 run({str(seed_file)!r}, "--out", "a.csv", "--plot", "a.csv/d.png"),
                 run({str(seed_file)!r}, "--plot", "f.svg", "--t-end", "0.5")]
        in_parent = "matplotlib" in sys.modules
        worker = plotworker.PlotWorker.start()
        os.kill(worker.pid, signal.SIGKILL)
        import kinetwork as kn
        res = kn.simulate(kn.load({str(seed_file)!r}), t_end=0.5, n_points=11)
        worker.save(res, "e.png", title="fallback")
        print(json.dumps([codes, in_parent]))
    """, tmp_path)
    codes, in_parent = json.loads(out.splitlines()[-1])
    assert codes == [0, 3, 1, 1, 0], err
    assert not in_parent
    assert out.count("wrote probe plots to a.png") == 1 and "b.png" in out
    assert "no probe or signal 'probe9'" in err and "cannot write a.csv/d.png" in err
    assert "Traceback" not in err
    import matplotlib.image as mpimg
    for name, width in [("a.png", 2160), ("b.png", 2160), ("e.png", 2160)]:
        image = mpimg.imread(tmp_path / name)
        assert image.shape[1] == width and image.std() > 0.05, name
    assert not (tmp_path / "c.png").exists()
    assert (tmp_path / "f.svg").read_text().lstrip().startswith("<?xml")


def test_the_drawing_process_is_asked_for_by_run_with_plot_only():
    """... and only for formats other than PNG, which the command draws itself (quickplot)."""
    assert plotworker.wanted(["run", "m.json", "--plot", "p.svg"])
    assert plotworker.wanted(["run", "m.json", "--plot=p.pdf"])
    assert not plotworker.wanted(["run", "m.json", "--plot", "p.png"])
    assert not plotworker.wanted(["run", "m.json", "--plot=P.PNG"])
    assert not plotworker.wanted(["run", "m.json", "--plot-signals", "probe1"])
    assert not plotworker.wanted(["validate", "m.json", "--plot", "p.png"])
    assert not plotworker.wanted([])


def test_formats_known_without_matplotlib_are_formats_it_writes():
    assert FORMATS <= set(FigureCanvasBase.get_supported_filetypes())


def boxes(fig):
    """(owner, box) of every visible text and legend of a drawn figure; owner ties the texts
    of one panel together (its title, labels, tick labels, legend)."""
    renderer = fig.canvas.get_renderer()
    found = []
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible():
            continue
        # the ticks drawn (get_ticklabels also returns spare ticks, left where they were)
        drawn = [tick.label1 for axis in (ax.xaxis, ax.yaxis) for tick in axis._update_ticks()]
        texts = [ax.title, ax.xaxis.label, ax.yaxis.label, ax.yaxis.offsetText, *drawn]
        found += [(k, t.get_window_extent(renderer)) for t in texts
                  if t.get_visible() and t.get_text()]
        if ax.get_legend() is not None:
            found.append((k, ax.get_legend().get_window_extent(renderer)))
    found += [("figure", t.get_window_extent(renderer)) for t in fig.texts if t.get_text()]
    found += [("figure", leg.get_window_extent(renderer)) for leg in fig.legends]
    return found


def overlap(a, b, slack=0.5):
    return (min(a.x1, b.x1) - max(a.x0, b.x0) > slack and
            min(a.y1, b.y1) - max(a.y0, b.y0) > slack)


@pytest.fixture(scope="module")
def runs():
    m = double_pendulum()
    m.add(kn.Probe("tip", quantities=["position", "velocity", "orientation"]))
    m.connect("tip.port", "elbow.frame_b")
    soft = kn.simulate(m, t_end=2.0, n_points=101)
    stiff = kn.simulate(m, t_end=2.0, n_points=101, params={"c": 20.0})
    return soft, stiff


def panel_share(fig):
    """The share of the figure's area the visible panels take."""
    area = sum(ax.bbox.width * ax.bbox.height for ax in fig.axes if ax.get_visible())
    return area / (fig.bbox.width * fig.bbox.height)


@pytest.mark.parametrize("case", ["seed", "vectors", "overlaid", "hidden", "tiny"])
def test_measured_margins_keep_every_text_apart_and_inside(runs, case):
    """A plot file has no layout engine: its margins are measured. Every text and legend lies
    inside the figure, off every panel, and clear of the texts of other panels; the panels
    take nearly as much of the figure as matplotlib's constrained layout gives them."""
    soft, stiff = runs

    def draw(detached):
        return {"seed": lambda: plot_results(soft, "probe1", "probe2", title="seed",
                                             _detached=detached),
                "vectors": lambda: plot_results(soft, "tip", title="tip", _detached=detached),
                "overlaid": lambda: plot_results([soft, stiff], labels=["c = 1", "c = 20"],
                                                 title="springs", _detached=detached),
                "hidden": lambda: plot_results(soft, "probe1", "probe2", hide_flat=True,
                                               _detached=detached),
                "tiny": lambda: plot_results(soft, "probe1.angle", columns=1,
                                             _detached=detached),
                }[case]()
    constrained = draw(False)
    constrained.canvas.draw()
    reference = panel_share(constrained)
    import matplotlib.pyplot as plt
    plt.close(constrained)
    fig = draw(True)
    FigureCanvasAgg(fig).draw()
    frame = fig.bbox
    found = boxes(fig)
    panels = [ax.bbox for ax in fig.axes if ax.get_visible()]
    for owner, box in found:
        assert box.x0 >= frame.x0 - 0.5 and box.x1 <= frame.x1 + 0.5, (owner, box)
        assert box.y0 >= frame.y0 - 0.5 and box.y1 <= frame.y1 + 0.5, (owner, box)
        assert not any(overlap(box, panel) for panel in panels), (owner, box)
    for i, (a, box_a) in enumerate(found):
        for b, box_b in found[i + 1:]:
            assert a == b or not overlap(box_a, box_b), (a, box_a, b, box_b)
    assert panel_share(fig) > 0.9 * reference, (panel_share(fig), reference)
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_xdata(), soft.t)


BLAS_SEEN = """
    import os, sys
    seen = []

    class Watch:                   # what OPENBLAS_THREAD_TIMEOUT is as numpy is imported
        def find_spec(self, name, path=None, target=None):
            if name == "numpy._core":              # (what numpy's __init__ imports first)
                seen.append(os.environ.get("OPENBLAS_THREAD_TIMEOUT"))
            return None
    sys.meta_path.insert(0, Watch())
"""


@pytest.mark.parametrize("chosen", [None, "28"])
def test_numpy_s_blas_threads_sleep_soon_unless_the_user_chose(seed_file, chosen):
    """OpenBLAS's idle threads spun 2^28 cycles (~0.1 s of CPU in every process) as numpy
    loaded: numpy's first import after kinetwork's has a shorter wait, the environment is as
    it was after it, and a value the user set is kept."""
    env = dict(ENV)
    env.pop("OPENBLAS_THREAD_TIMEOUT", None)
    if chosen is not None:
        env["OPENBLAS_THREAD_TIMEOUT"] = chosen
    code = BLAS_SEEN + f"""
    import kinetwork as kn
    from kinetwork.solver import jit       # numpy's first import, not through kn's names
    kn.load({str(seed_file)!r})
    print(seen, os.environ.get("OPENBLAS_THREAD_TIMEOUT"))
    """
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    during = chosen or str(kn.BLAS_THREAD_TIMEOUT)
    assert done.stdout.split() == [f"['{during}']", str(chosen)], done.stdout


def test_the_command_imports_numpy_as_kinetwork_does(seed_file, tmp_path):
    """The ``kinetwork`` command (``import numpy`` first nowhere on its way)."""
    env = dict(ENV)
    env.pop("OPENBLAS_THREAD_TIMEOUT", None)
    code = BLAS_SEEN + f"""
    from kinetwork.cli import main
    sys.argv = ["kinetwork", "run", {str(seed_file)!r}, "--t-end", "0.1", "--quiet"]
    code = main()
    print(code, seen, os.environ.get("OPENBLAS_THREAD_TIMEOUT"))
    """
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-2:] == [f"['{kn.BLAS_THREAD_TIMEOUT}']", "None"], done.stdout
