"""The command line's PNG plots drawn with Pillow (kinetwork/quickplot.py), checked against
matplotlib: the same pixel size and panel boxes as plot.py's figure, curves where the data
mapped through matplotlib's axis limits puts them, matplotlib's ticks and tick labels."""

import json
import os
import subprocess
import sys
import textwrap

import matplotlib
import numpy as np
import pytest
from PIL import Image

import kinetwork as kn
from kinetwork import plotlayout, quickplot
from kinetwork.plot import plot_results
from kinetwork.plotworker import PlotSignal
from kinetwork.solver.results import Results
from scenes import double_pendulum

matplotlib.use("Agg")
from matplotlib.ticker import MaxNLocator  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

BLUE = np.array([0x1F, 0x77, 0xB4])


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def synthetic(t, columns):
    """Results of one probe "p" on "joint.axis" from {quantity: (values, unit)}."""
    signals = [PlotSignal(f"p.{q}", unit, np.shape(v)[1:], int(np.prod(np.shape(v)[1:])),
                          "p", q) for q, (v, unit) in columns.items()]
    values = np.column_stack([np.reshape(v, (len(t), -1)) for v, _ in columns.values()])
    return Results(t, np.zeros((len(t), 0)), [], values, signals,
                   probe_targets={"p": "joint.axis"})


@pytest.fixture(scope="module")
def seed():
    return kn.simulate(double_pendulum(), t_end=2.0, n_points=201)


def matplotlib_boxes(results, **kwargs):
    """(size, boxes): plot.py's figure for a file, its pixel size at 150 dpi and the pixel
    boxes (x0, y0, x1, y1; y down) of its visible panels, row by row."""
    fig = plot_results(results, _detached=True, **kwargs)
    width, height = (round(v * 150) for v in fig.get_size_inches())
    boxes = []
    for ax in fig.axes:
        if ax.get_visible():
            x0, y0, w, h = ax.get_position().bounds
            boxes.append((x0 * width, (1 - y0 - h) * height, (x0 + w) * width,
                          (1 - y0) * height, ax.get_ylim()))
    return (width, height), boxes


def dark(image):
    return np.asarray(image.convert("L")) < 80


def frame(image, box, search=10):
    """The panel frame found in the image near ``box``: the dark column and row that run
    along most of the box's sides."""
    mask = dark(image)
    x0, y0, x1, y1 = (round(v) for v in box)

    def best(along, lo, hi, at):
        scores = [along(k).mean() for k in range(at - search, at + search + 1)]
        k = int(np.argmax(scores))
        assert scores[k] > 0.9, (at, max(scores))
        return at - search + k

    left = best(lambda x: mask[y0 + 5:y1 - 5, x], y0, y1, x0)
    right = best(lambda x: mask[y0 + 5:y1 - 5, x], y0, y1, x1)
    top = best(lambda y: mask[y, x0 + 5:x1 - 5], x0, x1, y0)
    bottom = best(lambda y: mask[y, x0 + 5:x1 - 5], x0, x1, y1)
    return left, top, right, bottom


@pytest.mark.parametrize("case", ["seed", "hidden"])
def test_the_png_has_matplotlib_s_size_and_panels(seed, case, tmp_path):
    """The file is as large as save_plot's, each panel's frame lies where plot.py's measured
    layout puts it (a few pixels apart: the texts are measured by another font engine), and
    its curve lies inside its frame."""
    kwargs = {"title": "double_pendulum", "hide_flat": case == "hidden"}
    quickplot.save_png(seed, tmp_path / "seed.png", **kwargs)
    with Image.open(tmp_path / "seed.png") as file:
        image = file.convert("RGB")
    size, boxes = matplotlib_boxes(seed, **kwargs)
    assert image.size == size
    assert len(boxes) == (7 if case == "hidden" else 8)
    pixels = np.asarray(image).astype(int)
    blue = (np.abs(pixels - BLUE).sum(axis=2) < 60)
    found = [frame(image, box) for *box, _ in boxes]
    for (*box, _), (left, top, right, bottom) in zip(boxes, found):
        np.testing.assert_allclose([left, top, right, bottom], box, atol=8)
        inside = blue[top + 2:bottom - 1, left + 2:right - 1]
        assert inside.any(axis=0).mean() > 0.95          # the curve spans the panel
    # and nothing blue outside them: curves are clipped to their panels
    assert blue.sum() == sum(blue[t:b + 1, l:r + 1].sum() for l, t, r, b in found)


def test_curves_lie_where_matplotlib_s_axis_limits_map_the_data_and_nan_leaves_gaps(tmp_path):
    t = np.linspace(0.0, 2.0, 401)
    angle = 0.3 + 0.05 * np.sin(np.pi * t)
    angle[(t > 1.2) & (t < 1.5)] = np.nan                       # a gap, as a partial run has
    run = synthetic(t, {"angle": (angle, "rad"), "speed": (-3e-7 * np.cos(t), "rad/s")})
    quickplot.save_png(run, tmp_path / "s.png")
    with Image.open(tmp_path / "s.png") as file:
        image = file.convert("RGB")
    _, boxes = matplotlib_boxes(run)
    pixels = np.asarray(image).astype(int)
    blue = np.abs(pixels - BLUE).sum(axis=2) < 120
    for (*box, (lo, hi)), values in zip(boxes, [angle, run["p.speed"]]):
        left, top, right, bottom = frame(image, box)
        checked, errors = 0, []
        for x in range(left + 6, right - 5):
            tx = (x - left) / (right - left) * 2.0      # pixel centres, the frame's too
            v = np.interp(tx, t, values)
            column = np.flatnonzero(blue[top + 2:bottom - 1, x])
            if not np.isfinite(v) or abs(tx - 1.2) < 0.02 or abs(tx - 1.5) < 0.02:
                continue
            expected = bottom - (v - lo) / (hi - lo) * (bottom - top) - top - 2
            assert column.size, x
            errors.append(column.mean() - expected)
            checked += 1
        # a 3 px wide line, antialiased, on slopes up to 2 px per px: its centre within 1.5 px;
        # on average within the half pixel to which the frame is found
        assert checked > 0.8 * (right - left)
        assert np.max(np.abs(errors)) < 1.5 and abs(np.mean(errors)) < 0.5, errors
    left, top, right, bottom = frame(image, boxes[0][:4])
    gap = [x for x in range(left, right) if 1.23 < (x - left) / (right - left) * 2.0 < 1.47]
    assert len(gap) > 20 and not blue[top + 2:bottom - 1, gap].any()


CASES = [(0.0, 1.0), (-0.055, 0.055), (-0.0498, 0.0545), (-1.23, 0.87), (0.2, 0.85),
         (-60.3, 52.1), (1.5, 2.05), (-3.3e-7, 3.1e-7), (2e6, 9e6), (0.9995, 1.0012),
         (-4.4, 1.02), (0.0, 10.0), (0.0, 0.99), (-1e-5, 2.4e-5), (120.0, 180.0)]


@pytest.mark.parametrize("bins", [3, 5, 9])
def test_ticks_and_labels_are_matplotlib_s(bins):
    """AutoLocator's 1-2-2.5-5 steps covering the range, and ScalarFormatter's labels (one
    number of decimals per axis, "1e−7" above scaled ones), against matplotlib itself."""
    rng = np.random.default_rng(bins)
    cases = CASES + [tuple(sorted(rng.normal(size=2) * 10.0 ** rng.integers(-8, 8)))
                     for _ in range(30)]
    _, ax = plt.subplots()
    for low, high in cases:
        locator = MaxNLocator(nbins=bins, steps=[1, 2, 2.5, 5, 10])
        ax.yaxis.set_major_locator(locator)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.set_ylim(low, high)
        expected = locator.tick_values(low, high)
        ticks = plotlayout.nice_ticks(low, high, bins * 20.0 + 1.0, 10.0, 2)
        np.testing.assert_allclose(ticks, expected, rtol=1e-12, atol=1e-12 * (high - low))
        step = np.diff(ticks)[0]
        mantissa = step / 10.0 ** np.floor(np.log10(step) + 1e-9)
        assert min(abs(mantissa - m) for m in (1, 2, 2.5, 5)) < 1e-9
        assert ticks[0] <= low + 1e-9 * step and ticks[-1] >= high - 1e-9 * step
        formatter = ax.yaxis.get_major_formatter()
        labels = formatter.format_ticks(expected)
        mine, offset = plotlayout.tick_labels(ticks, low, high)
        assert mine == labels, (low, high)
        assert offset == formatter.get_offset(), (low, high)


def test_what_the_light_renderer_draws_and_what_it_leaves_to_matplotlib(seed, tmp_path):
    tip = double_pendulum()
    tip.add(kn.Probe("tip", quantities=["position", "orientation"]))
    tip.connect("tip.port", "elbow.frame_b")
    frames = kn.simulate(tip, t_end=0.2, n_points=11)
    assert quickplot.drawable("a.png", seed) and quickplot.drawable("A.PNG", seed)
    assert quickplot.drawable("a.png", frames, ["tip.position"])
    assert not quickplot.drawable("a.svg", seed) and not quickplot.drawable("a.pdf", seed)
    assert not quickplot.drawable("a.png", frames)                 # nine dashed curves
    assert not quickplot.drawable("a.png", [seed, seed])           # overlaid runs
    assert not quickplot.drawable("a.png", seed, ["probe9"])       # save_plot refuses it
    late = synthetic(np.linspace(1e4, 1e4 + 1.0, 11), {"angle": (np.ones(11), "rad")})
    assert not quickplot.drawable("a.png", late)                   # an offset time axis
    with pytest.raises(kn.ModelError, match="every signal asked for is constant"):
        quickplot.save_png(late, tmp_path / "c.png", hide_flat=True)


ENV = dict(os.environ, KINETWORK_JIT="0")


def test_the_command_line_draws_a_png_without_matplotlib_scipy_or_a_second_process(tmp_path):
    """... and hands a PNG the light renderer does not draw (an orientation) to matplotlib."""
    double_pendulum().save(tmp_path / "seed.json")
    tip = double_pendulum()
    tip.add(kn.Probe("tip", quantities=["orientation"]))
    tip.connect("tip.port", "elbow.frame_b")
    tip.save(tmp_path / "tip.json")
    code = textwrap.dedent("""
        import json, os, sys
        def no_fork():
            raise AssertionError("forked")
        os.fork = no_fork
        from kinetwork import cli
        def run(model, png):
            sys.argv = ["kinetwork", "run", model, "--t-end", "1", "--plot", png, "--quiet"]
            return cli.main()
        code = run("seed.json", "s.png")
        loaded = sorted(m for m in ("matplotlib", "scipy") if m in sys.modules)
        print(json.dumps([code, loaded, run("tip.json", "t.png")]))
    """)
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=ENV, check=False,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.splitlines()[-1]) == [0, [], 0]
    with Image.open(tmp_path / "s.png") as image:
        assert image.size == (2160, 825) and image.info["Software"] == "kinetwork"
    with Image.open(tmp_path / "t.png") as image:
        assert image.info["Software"].startswith("Matplotlib")
