"""Probe plots: layout, labels and data of the figure, and the image file."""

import subprocess
import sys

import matplotlib
import numpy as np
import pytest

import kinetwork as kn
from kinetwork.plot import save_plot, unit_label
from scenes import double_pendulum

matplotlib.use("Agg")                        # tests never open windows
import matplotlib.pyplot as plt  # noqa: E402

QUANTITIES = ["angle", "speed", "acceleration", "torque"]
FRAME = ["position", "velocity", "acceleration", "orientation", "angular_velocity"]


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def seed_results():
    return kn.simulate(double_pendulum(), t_end=2.0, n_points=201)


@pytest.fixture(scope="module")
def tip_results():
    """The seed plus a frame probe on the elbow: vectors and an orientation."""
    m = double_pendulum()
    m.add(kn.Probe("tip", quantities=FRAME))
    m.connect("tip.port", "elbow.frame_b")
    return kn.simulate(m, t_end=1.0, n_points=51)


def visible(fig):
    return [ax for ax in fig.axes if ax.get_visible()]


def test_seed_layout_is_the_papers(seed_results):
    """Two probes, four quantities: a 2 x 4 grid, like the paper's Figs. 5 and 6."""
    fig = seed_results.plot()
    axes = np.array(fig.axes).reshape(2, 4)
    assert [[ax.get_title() for ax in row] for row in axes] == [
        [f"{p} ({joint}.axis): {q}" for q in QUANTITIES]
        for p, joint in (("probe1", "shoulder"), ("probe2", "elbow"))]
    assert [ax.get_ylabel() for ax in axes[0]] == [
        "angle [rad]", "speed [rad/s]", "acceleration [rad/s\u00b2]", "torque [N\u00b7m]"]
    assert [ax.get_xlabel() for ax in axes[1]] == ["time [s]"] * 4
    assert [ax.get_xlabel() for ax in axes[0]] == [""] * 4
    for (i, j), probe in zip(np.ndindex(2, 4), ["probe1"] * 4 + ["probe2"] * 4):
        [line] = axes[i, j].get_lines()
        np.testing.assert_array_equal(line.get_xdata(), seed_results.t)
        np.testing.assert_array_equal(line.get_ydata(),
                                      seed_results[f"{probe}.{QUANTITIES[j]}"])
        assert axes[i, j].xaxis.get_gridlines()[0].get_visible()
    assert axes[0, 0].get_xlim() == (0.0, 2.0)
    width, height = fig.get_size_inches()
    assert width > 2 * height


def test_select_probes_in_order(seed_results):
    fig = seed_results.plot(probes=["probe2"], title="elbow", linewidth=3)
    assert [ax.get_title() for ax in visible(fig)] == [f"probe2 (elbow.axis): {q}" for q in QUANTITIES]
    assert fig.axes[0].get_lines()[0].get_linewidth() == 3
    assert fig.get_suptitle() == "elbow"
    fig = seed_results.plot(probes="probe1")
    assert len(visible(fig)) == 4


def test_unknown_probe_is_refused_with_a_suggestion(seed_results):
    with pytest.raises(kn.ModelError, match=r"no probe or signal 'prob1' \(did you mean 'probe1'\?\)"):
        seed_results.plot(probes=["prob1"])


def test_results_without_probes_are_refused():
    res = kn.simulate(double_pendulum(probes=False), t_end=0.5, n_points=11)
    with pytest.raises(kn.ModelError, match="no probes"):
        res.plot()


def test_vectors_orientation_and_wrapping(tip_results):
    """Five frame quantities wrap onto a second row; vectors get x/y/z, R its nine entries."""
    fig = tip_results.plot(probes=["probe1", "tip"])
    axes = np.array(fig.axes).reshape(3, 4)
    assert [ax.get_title() for ax in axes[1]] == [f"tip (elbow.frame_b): {q}" for q in FRAME[:4]]
    assert axes[2, 0].get_title() == "tip (elbow.frame_b): angular velocity"
    assert axes[2, 0].get_ylabel() == "angular velocity [rad/s]"
    assert not any(ax.get_visible() for ax in axes[2, 1:])
    position = axes[1, 0]
    assert [t.get_text() for t in position.get_legend().get_texts()] == ["x", "y", "z"]
    for k, line in enumerate(position.get_lines()):
        np.testing.assert_array_equal(line.get_ydata(), tip_results["tip.position"][:, k])
    orientation = axes[1, 3]
    assert len(orientation.get_lines()) == 9
    assert orientation.get_ylim() == (-1.1, 1.1)
    r23 = [ln for ln in orientation.get_lines() if ln.get_label() == "R23"][0]
    np.testing.assert_array_equal(r23.get_ydata(), tip_results["tip.orientation"][:, 1, 2])
    # "time [s]" where each column ends: row 3 for the first column, row 2 for the others
    assert axes[2, 0].get_xlabel() == "time [s]" and axes[1, 0].get_xlabel() == ""
    assert [ax.get_xlabel() for ax in axes[1, 1:]] == ["time [s]"] * 3


def test_constant_signal_has_no_offset_label(seed_results):
    """The seed's elbow torque is 0 throughout: plain ticks, no '1e-16 + offset'."""
    fig = seed_results.plot(probes=["probe2"])
    fig.canvas.draw()
    torque = fig.axes[3]
    assert torque.yaxis.get_offset_text().get_text() == ""


def test_save_plot_writes_png_and_closes(seed_results, tmp_path):
    before = plt.get_fignums()
    path = tmp_path / "probes.png"
    save_plot(seed_results, path, title="double_pendulum")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert plt.get_fignums() == before
    save_plot(seed_results, tmp_path / "probes.svg")
    assert "<svg" in (tmp_path / "probes.svg").read_text()


def test_save_plot_refuses_unknown_format(seed_results, tmp_path):
    with pytest.raises(kn.ModelError, match="cannot write a plot as 'xyz'.*png"):
        save_plot(seed_results, tmp_path / "probes.xyz")
    assert not (tmp_path / "probes.xyz").exists()


def test_unit_labels():
    assert unit_label("rad/s^2") == "rad/s\u00b2"
    assert unit_label("N*m*s/rad") == "N\u00b7m\u00b7s/rad"
    assert unit_label("") == ""


def test_import_does_not_load_matplotlib():
    """Plots are thin and lazy: importing kinetwork leaves matplotlib alone."""
    code = "import sys, kinetwork; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_single_point_results_plot_without_warnings():
    """A run that fails at once leaves one point: still a figure, no singular-limits warning."""
    system = double_pendulum().compile()
    res = kn.simulate(system, t_end=0.1, n_points=2)
    one = kn.Results(res.t[:1], res.states[:1], res.state_names, res.columns()[1][:1, 1:],
                     system.signals)
    fig = one.plot()
    fig.canvas.draw()
    assert len(visible(fig)) == 8


def test_select_quantities_by_name_and_states(seed_results):
    fig = seed_results.plot("probe1.angle", "probe2.torque")
    assert [ax.get_title() for ax in visible(fig)] == ["probe1 (shoulder.axis): angle",
                                                      "probe2 (elbow.axis): torque"]
    fig = seed_results.plot(seed_results.state_names[0])
    [ax] = visible(fig)
    np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), seed_results.states[:, 0])
    assert ax.get_ylabel().endswith("[rad]")


def test_small_probes_share_rows(tip_results):
    """Probes with fewer quantities than a row share rows (arm_pid's four signal probes of
    one value each fill one row instead of four mostly empty ones)."""
    model = double_pendulum()
    for k in range(4):
        model.add(kn.Probe(f"p{k}", quantities=["angle"]))
        model.connect(f"p{k}.port", "shoulder.axis")
    res = kn.simulate(model, t_end=0.2, n_points=11)
    fig = res.plot()
    axes = np.array(fig.axes).reshape(3, 4)
    assert all(ax.get_visible() for ax in axes.ravel())
    assert [ax.get_title().split(" ")[0] for ax in axes[2]] == ["p0", "p1", "p2", "p3"]
    fig = res.plot("probe1", "p0", columns=2)
    assert np.array(fig.axes).shape == (6,) and len(visible(fig)) == 5


def test_overlaid_runs_share_panels_with_one_legend():
    soft = kn.simulate(double_pendulum(), t_end=1.0, n_points=51)
    stiff_model = double_pendulum()
    stiff = kn.simulate(stiff_model, t_end=1.0, n_points=51, params={"c": 20.0})
    fig = kn.plot([soft, stiff], "probe1.angle", labels=["c = 1", "c = 20"], title="springs")
    [ax] = visible(fig)
    soft_line, stiff_line = ax.get_lines()
    np.testing.assert_array_equal(soft_line.get_ydata(), soft["probe1.angle"])
    np.testing.assert_array_equal(stiff_line.get_ydata(), stiff["probe1.angle"])
    assert soft_line.get_color() != stiff_line.get_color()
    [legend] = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == ["c = 1", "c = 20"]
    assert fig.get_suptitle() == "springs"
    with pytest.raises(kn.ModelError, match="1 labels for 2 runs"):
        kn.plot([soft, stiff], labels=["one"])


def test_hide_flat_drops_dead_panels_and_names_them(seed_results):
    """The seed's elbow torque is 0 throughout: hidden on request, named under the figure."""
    fig = seed_results.plot(hide_flat=True)
    titles = [ax.get_title() for ax in visible(fig)]
    assert "probe2 (elbow.axis): torque" not in titles and len(titles) == 7
    assert any("constant, not drawn: probe2.torque = 0" in t.get_text() for t in fig.texts)
    assert len(visible(seed_results.plot())) == 8


def test_component_legends_sit_outside_the_data(tip_results):
    """Legends of x/y/z are placed right of the axes, never over the curves."""
    fig = tip_results.plot("tip.position", "tip.orientation")
    fig.canvas.draw()
    for ax in visible(fig):
        legend = ax.get_legend().get_window_extent()
        assert legend.x0 >= ax.get_window_extent().x1


def test_signal_panels_carry_the_unit_their_wires_give():
    res = kn.simulate(kn.load("models/arm_pid.json"), t_end=0.1, n_points=11)
    fig = res.plot("command_shoulder", "reference_shoulder")
    assert [ax.get_ylabel() for ax in visible(fig)] == ["value [N\u00b7m]", "value [rad]"]
