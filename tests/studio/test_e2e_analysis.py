"""Analysis from the page (issue 29 item 6), in headless Chromium: a parameter sweep, on a
grid and drawn at random, whose members are overlaid in the plots and equal kn.sweep's; the
model linearised (poles, Bode plot) as kn.linearize gives it; a 1-D model's 3-D view says
there is nothing to show."""

import json

import numpy as np

import kinetwork as kn
from tests.studio.helpers import (RUN_TIMEOUT, K, deselect, open_studio, place, run,
                                  screenshot, set_field, tid, wire)

SEED = "models/double_pendulum.json"


def short(page):
    deselect(page)
    set_field(page, "sim-t_end", "2")
    set_field(page, "sim-n_points", "201")


def wait_sweep(page):
    page.wait_for_function("() => { const s = window.__kinetwork.runState; return s && "
                           "s.kind === 'sweep' && ['done', 'failed', 'cancelled'].includes(s.state);"
                           " }", timeout=RUN_TIMEOUT)
    return K(page, "K.runState.state")


def test_a_grid_sweep_from_the_page_plots_its_members_as_kn_sweep_gives_them(page, studio):
    open_studio(page, studio, open=SEED)
    short(page)
    page.click(tid("tab-analysis"))
    page.select_option(tid("sweep-param-0"), "c")
    page.fill(tid("sweep-values-0"), "1, 4")
    page.click(tid("sweep-add"))
    page.select_option(tid("sweep-param-1"), "d")
    page.fill(tid("sweep-values-1"), "0.2 .. 1 / 3")
    assert "6 members" in page.locator(tid("sweep-run")).inner_text()
    page.click(tid("sweep-run"))
    assert wait_sweep(page) == "done", K(page, "K.runState")
    entry = K(page, "K.runs[0]")
    assert entry["kind"] == "sweep" and len(entry["members"]) == 6
    assert entry["label"] == "sweep 1 · 6 members"
    # the same members, the same numbers as kn.sweep
    model = kn.load(studio.root / SEED)
    ds = kn.sweep(model, {"c": [1.0, 4.0], "d": [0.2, 0.6, 1.0]}, t_end=2.0, n_points=201,
                  progress=False)
    for m in entry["members"]:
        assert m["status"] == "ok"
        got = next(s for s in m["results"]["signals"] if s["name"] == "probe1.angle")["values"]
        want = ds["probe1.angle"].sel(c=m["params"]["c"], d=m["params"]["d"],
                                      method="nearest").values
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    # overlaid: six curves of probe1 and six of probe2 in the angle panel, named by values
    assert K(page, "K.plottedSeries.angle") == 12
    legend = page.locator(f'{tid("plot-angle")} .u-legend').inner_text()
    assert "c = 1, d = 0.2" in legend and "c = 4, d = 1" in legend
    screenshot(page, "studio-sweep.png")
    assert not page.errors, page.errors


def test_a_random_sweep_draws_its_members_repeatably(page, studio):
    open_studio(page, studio, open=SEED)
    short(page)
    page.click(tid("tab-analysis"))
    page.click(tid("sweep-kind-random"))
    page.select_option(tid("sweep-param-0"), "c")
    page.fill(tid("sweep-a-0"), "0.5")
    page.fill(tid("sweep-b-0"), "2")
    page.fill(tid("sweep-n"), "4")
    page.fill(tid("sweep-seed"), "7")
    page.click(tid("sweep-run"))
    assert wait_sweep(page) == "done"
    drawn = [m["params"]["c"] for m in K(page, "K.runs[0].members")]
    ds = kn.sample(kn.load(studio.root / SEED), {"c": kn.uniform(0.5, 2.0)}, 4, seed=7,
                   t_end=2.0, n_points=201, progress=False)
    np.testing.assert_allclose(drawn, ds["c"].values, rtol=1e-12)
    assert all(0.5 <= c <= 2 for c in drawn)
    assert not page.errors, page.errors


def test_linearize_at_the_cursor_gives_kn_linearizes_poles_and_a_bode_plot(page, studio):
    open_studio(page, studio)
    place(page, "multibody.Ground", "ground", 60, 100)
    place(page, "multibody.Revolute", "joint", 260, 100)
    place(page, "multibody.BodyShape", "arm", 460, 100)
    place(page, "rotational.Torque", "motor", 260, 300)
    place(page, "Probe", "probe", 460, 300)
    for a, b in (("ground.frame", "joint.frame_a"), ("joint.frame_b", "arm.frame_a"),
                 ("motor.flange", "joint.axis"), ("probe.port", "joint.axis")):
        wire(page, a, b)
    page.wait_for_function("() => window.__kinetwork.doc.connections.length === 4")
    page.click(f'{tid("node-arm")} .kn-block-name')
    set_field(page, "param-r", "[0.5, 0, 0]")
    set_field(page, "param-mass", "2")
    set_field(page, "param-r_cm", "[0.25, 0, 0]")
    page.click(f'{tid("node-joint")} .kn-block-name')
    set_field(page, "param-q0", "-1.2")
    page.click(f'{tid("node-probe")} .kn-block-name')
    page.check(tid("param-quantities-angle"))
    page.wait_for_function("() => window.__kinetwork.validated && window.__kinetwork.validation.ok")
    assert run(page) == "done"
    # the plot cursor at t = 1.5 s, moved by the mouse
    box = page.locator(f'{tid("plot-angle")} .u-over').bounding_box()
    page.mouse.move(box["x"] + box["width"] * 1.5 / 10, box["y"] + box["height"] / 2)
    page.wait_for_function("() => Math.abs(window.__kinetwork.cursorTime - 1.5) < 0.1")
    at = K(page, "K.cursorTime")
    page.click(tid("tab-analysis"))
    page.check(tid("lin-input-motor.u"))
    page.click(tid("lin-run"))
    page.wait_for_selector(tid("lin-result"), timeout=RUN_TIMEOUT)
    shown = page.locator(tid("lin-poles")).inner_text()
    lin = kn.linearize(kn.loads(json.dumps(K(page, "K.doc"))), at=at, inputs=["motor.u"])
    assert len(page.locator(f'{tid("lin-poles")} tr').all()) == len(lin.eigenvalues)
    for p in lin.eigenvalues:
        assert f"{abs(p.imag):.4f}" in shown or f"{p.real:.4f}" in shown
    page.wait_for_selector(tid("bode-mag"))
    page.wait_for_selector(f'{tid("bode-phase")} canvas')
    assert "motor.u" in page.locator(tid("bode")).inner_text()
    screenshot(page, "studio-linearize.png")
    assert not page.errors, page.errors


def test_a_1d_model_runs_and_its_3d_view_says_there_is_nothing_to_show(page, studio):
    open_studio(page, studio, open="models/msl_friction.json")
    deselect(page)
    set_field(page, "sim-t_end", "0.5")
    assert run(page) == "done"
    # the plots come first ("The 3-D view is on its way…" meanwhile), then the view's note
    page.locator(tid("viewer-note")).filter(has_text="nothing to show in 3-D").wait_for()
    assert not page.errors, page.errors
