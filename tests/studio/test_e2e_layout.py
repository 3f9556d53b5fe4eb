"""The studio's layout and diagrams in the browser (issue 29 items 3 and 4): an icon of its own
for every component type, and a page that fits at the window sizes people use.

Everything here is read from the rendered page (element rectangles, SVG attributes), with
real mouse events where the user would act."""

import csv
import io
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from tests.studio.helpers import K, open_studio, run, screenshot, select, set_field, tid

SEED = "models/double_pendulum.json"
SIZES = [(1000, 700), (1400, 900), (1920, 1080)]
#: the page's panes, each holding its controls
PANES = {"bar": ".kn-bar", "palette": tid("palette"), "diagram": tid("canvas"),
         "plots": tid("plots"), "viewer": tid("viewer"), "side": ".kn-right"}

#: where each control is, from the page's element rectangles: its pane, its own rectangle,
#: and the scrolling box (below the pane) it may lie in; controls hidden by display or a
#: closed pane are not there to click
PLACES = """(panes) => {
    const box = (el) => { const r = el.getBoundingClientRect();
        return {x0: r.left, y0: r.top, x1: r.right, y1: r.bottom}; };
    const scrolls = (el) => { const s = getComputedStyle(el);
        return {x: /auto|scroll/.test(s.overflowX) && el.scrollWidth > el.clientWidth,
                y: /auto|scroll/.test(s.overflowY) && el.scrollHeight > el.clientHeight}; };
    const out = {viewport: {x0: 0, y0: 0, x1: innerWidth, y1: innerHeight}, panes: {}, controls: []};
    for (const [name, sel] of Object.entries(panes)) {
        const pane = document.querySelector(sel);
        if (!pane) continue;
        out.panes[name] = box(pane);
        const controls = pane.querySelectorAll("button, input, select, textarea, [role=tab]");
        for (const c of controls) {
            if (!c.getClientRects().length || getComputedStyle(c).visibility === "hidden") continue;
            let scroller = null;
            for (let up = c.parentElement; up && up !== pane; up = up.parentElement) {
                const s = scrolls(up);
                if (s.x || s.y) { scroller = {box: box(up), ...s}; break; }
            }
            const label = c.dataset.testid || c.title || c.textContent.trim().slice(0, 20) || c.tagName;
            out.controls.push({pane: name, label, box: box(c), scroller});
        }
    }
    return out;
}"""


def inside(a, b, along="xy", slack=0.5):
    """Whether the rectangle ``a`` lies in ``b`` along the axes named."""
    return all(a[f"{k}0"] >= b[f"{k}0"] - slack and a[f"{k}1"] <= b[f"{k}1"] + slack
               for k in along)


def misplaced(page):
    """Every pane outside the window, and every control outside its pane: a control in a
    box that scrolls is reached by scrolling along that box's scrolling axis, and must lie
    within it along the other."""
    places = page.evaluate(PLACES, PANES)
    wrong = [f"pane {name} {b}" for name, b in places["panes"].items()
             if not inside(b, places["viewport"])]
    for c in places["controls"]:
        pane = places["panes"][c["pane"]]
        s = c["scroller"]
        if s is None:
            ok = inside(c["box"], pane)
        else:
            fixed = "".join(k for k in "xy" if not s[k])
            ok = inside(s["box"], pane) and inside(c["box"], s["box"], fixed)
        if not ok:
            wrong.append(f"{c['pane']}: {c['label']!r} at {c['box']}")
    return wrong, places


def plot_axes_wrong(page, key_prefix=""):
    """Each plot's y axis with fewer than three ticks, or labels wider than the axis; x
    labels that run into each other."""
    axes = K(page, "K.plotAxes")
    widths = page.evaluate("""(axes) => {
        const ctx = document.createElement("canvas").getContext("2d");
        const out = {};
        for (const [k, a] of Object.entries(axes)) { ctx.font = a.font;
            out[k] = {x: a.x.labels.map(l => ctx.measureText(l).width),
                      y: a.y.labels.map(l => ctx.measureText(l).width)}; }
        return out; }""", axes)
    wrong = []
    for key, a in axes.items():
        if not key.startswith(key_prefix):
            continue
        if len(a["y"]["ticks"]) < 3:
            wrong.append(f"{key}: y ticks {a['y']['labels']}")
        if max(widths[key]["y"], default=0) + 6 + 5 > a["ySize"]:
            wrong.append(f"{key}: y labels {a['y']['labels']} wider than the axis ({a['ySize']} px)")
        xs, lo, hi = a["x"]["ticks"], a["x"]["min"], a["x"]["max"]
        plot_w = page.evaluate("(k) => { const el = document.querySelector(`[data-testid='${k}'] .u-over`);"
                               " return el ? el.getBoundingClientRect().width : 0; }",
                               ("bigplot-" + key[4:]) if key.startswith("big:") else f"plot-{key}")
        at = [(x - lo) / (hi - lo) * plot_w for x in xs]
        for i in range(len(at) - 1):
            if at[i + 1] - at[i] < (widths[key]["x"][i] + widths[key]["x"][i + 1]) / 2 + 4:
                wrong.append(f"{key}: x labels {a['x']['labels'][i:i + 2]} overlap")
    return wrong, axes


def schema_types(page):
    """The component types /api/schema lists, as the page's own request gets them."""
    return page.evaluate("""async () => {
        const token = new URLSearchParams(location.search).get("token");
        const s = await (await fetch("/api/schema", {headers: {"X-Kinetwork-Token": token}})).json();
        // the library's types (the last choice is a subsystem's, any definition name)
        return s.properties.components.items.oneOf.map(o => o.properties.type.const).filter(Boolean);
    }""")


def test_every_type_of_the_schema_has_an_icon_of_its_own(page, studio):
    """Each type /api/schema names is in the palette with a drawn icon, never the "?"
    fallback; two libraries' grounds differ, and a block on the diagram shows its type's."""
    open_studio(page, studio)
    types = schema_types(page)
    assert len(types) > 100
    icons = page.evaluate("""(types) => Object.fromEntries(types.map(t => {
        const item = document.querySelector(`[data-testid="palette-${t}"]`);
        const svg = item && item.querySelector("svg[data-icon]");
        return [t, svg ? [svg.dataset.icon, svg.querySelectorAll("path, circle, rect, ellipse, text").length] : null];
    }))""", types)
    missing = [t for t, icon in icons.items() if icon is None]
    assert not missing, f"not in the palette: {missing}"
    fallback = sorted(t for t, (key, _) in icons.items() if key == "Unknown")
    assert not fallback, f"types drawn with the '?' fallback: {fallback}"
    empty = sorted(t for t, (_, shapes) in icons.items() if shapes == 0)
    assert not empty, f"icons that draw nothing: {empty}"
    assert icons["electrical.Ground"][0] != icons["multibody.Ground"][0]

    page.fill(tid("palette-search"), "PointMass")
    page.wait_for_selector(tid("palette-multibody.PointMass"))
    page.dblclick(tid("palette-multibody.PointMass"))
    page.wait_for_function("() => window.__kinetwork.doc.components.length === 1")
    name = K(page, "K.doc.components[0].name")
    assert page.get_attribute(f'{tid(f"node-{name}")} svg[data-icon]', "data-icon") == "PointMass"
    assert not page.errors, page.errors


@pytest.mark.parametrize("width,height", SIZES)
def test_every_control_lies_in_its_pane_and_every_plot_has_three_ticks(page, studio, width,
                                                                        height):
    """At 1000x700, 1400x900 and 1920x1080, the seed opened and run: every pane in the
    window, every control within its pane (or its scrolling box), the file's name shown,
    every plot with at least three y ticks whose labels fit the axis and x labels apart."""
    page.set_viewport_size({"width": width, "height": height})
    open_studio(page, studio, open=SEED)
    assert run(page) == "done"
    page.wait_for_selector(f'{tid("viewer")}[data-ready="1"]')
    page.wait_for_selector(".kn-viewer-bar")
    page.wait_for_function("() => Object.keys(window.__kinetwork.plotAxes).length >= 3")
    wrong, places = misplaced(page)
    assert not wrong, wrong
    assert {"bar", "palette", "diagram", "plots", "viewer", "side"} <= set(places["panes"])
    viewer_buttons = [c["label"] for c in places["controls"] if c["pane"] == "viewer"]
    assert len(viewer_buttons) >= 5, viewer_buttons            # play, time, speed, frames, view
    name = page.locator(f'{tid("file")} b').bounding_box()
    assert name["width"] > 50 and name["x"] + name["width"] <= width
    plots = page.locator(tid("plots")).bounding_box()
    assert plots["height"] >= 150, plots
    wrong, axes = plot_axes_wrong(page)
    assert not wrong, wrong
    assert len(axes) >= 3
    minimap = page.locator(".react-flow__minimap")
    if minimap.count():               # shown only where it leaves the diagram room
        canvas = page.locator(tid("canvas")).bounding_box()
        mini = minimap.bounding_box()
        assert mini["width"] * mini["height"] < 0.12 * canvas["width"] * canvas["height"]
    screenshot(page, f"studio-{width}x{height}.png")
    assert not page.errors, page.errors


def width_of(page, testid_or_css):
    return page.locator(testid_or_css).bounding_box()["width"]


def drag(page, selector, dx, dy):
    box = page.locator(selector).bounding_box()
    # beside the splitter's arrow button, which a press on would not drag
    x, y = box["x"] + box["width"] / 2, box["y"] + min(40, box["height"] / 4)
    if box["width"] > box["height"]:
        x, y = box["x"] + min(60, box["width"] / 4), box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + dx / 2, y + dy / 2, steps=4)
    page.mouse.move(x + dx, y + dy, steps=4)
    page.mouse.up()


def test_panes_resize_collapse_and_are_remembered(page, studio):
    """Dragging the splitters resizes the palette, the plots and the 3-D view; their arrows
    collapse the side panel and the 3-D view; reloading the page keeps all of it, and the
    arrows bring the panes back."""
    page.set_viewport_size({"width": 1400, "height": 900})
    open_studio(page, studio, open=SEED)
    palette = width_of(page, tid("palette"))
    results = page.locator(".kn-results").bounding_box()["height"]
    drag(page, tid("splitter-palette"), 60, 0)
    page.wait_for_function(f"() => document.querySelector('[data-testid=palette]')"
                           f".getBoundingClientRect().width > {palette + 50}")
    drag(page, tid("splitter-results"), 0, -100)
    page.wait_for_function(f"() => document.querySelector('.kn-results')"
                           f".getBoundingClientRect().height > {results + 90}")
    viewer = width_of(page, tid("viewer"))
    drag(page, tid("splitter-viewer"), -80, 0)
    page.wait_for_function(f"() => document.querySelector('[data-testid=viewer]')"
                           f".getBoundingClientRect().width > {viewer + 70}")
    canvas = width_of(page, tid("canvas"))
    page.click(tid("toggle-side"))
    page.wait_for_selector(".kn-right", state="detached")
    assert width_of(page, tid("canvas")) > canvas + 200
    sizes = {"palette": width_of(page, tid("palette")), "viewer": width_of(page, tid("viewer")),
             "results": page.locator(".kn-results").bounding_box()["height"],
             "canvas": width_of(page, tid("canvas"))}

    page.reload()
    page.wait_for_selector(f'{tid("palette")}[data-ready="1"]')
    page.wait_for_selector(tid("node-spring"))
    assert page.locator(".kn-right").count() == 0
    again = {"palette": width_of(page, tid("palette")), "viewer": width_of(page, tid("viewer")),
             "results": page.locator(".kn-results").bounding_box()["height"],
             "canvas": width_of(page, tid("canvas"))}
    for key, value in sizes.items():
        assert abs(again[key] - value) <= 1, (key, value, again[key])
    page.click(tid("toggle-side"))
    page.wait_for_selector(".kn-right")
    page.dblclick(tid("splitter-viewer"))
    page.wait_for_selector(tid("viewer"), state="detached")
    page.click(tid("toggle-viewer"))
    page.wait_for_selector(tid("viewer"))
    wrong, _ = misplaced(page)
    assert not wrong, wrong
    assert not page.errors, page.errors


def download(page, testid):
    with page.expect_download() as info:
        page.click(tid(testid))
    d = info.value
    return d.suggested_filename, pathlib.Path(d.path()).read_bytes()


def test_overlaid_runs_have_a_legend_exports_and_a_larger_plot(page, studio):
    """Two runs overlaid: the legend names each run and the parameter that differs; the
    angle plot's CSV holds the plotted numbers of both runs, its SVG draws each curve with
    its name, its PNG is a picture of the plot; the larger plot has more ticks, all fitting."""
    page.set_viewport_size({"width": 1400, "height": 900})
    open_studio(page, studio, open=SEED)
    assert run(page) == "done"
    select(page, "spring")
    set_field(page, "param-c", "5")
    assert run(page) == "done"
    legend = page.locator(f'{tid("plot-angle")} .u-legend .u-series th').all_inner_texts()
    names = [n.strip() for n in legend[1:]]
    assert any("run 2" in n and "spring.c = 5" in n for n in names), names
    assert any("run 1" in n for n in names), names
    assert len(names) == 4, names                   # two probes in each of the two runs

    name, data = download(page, "plot-angle-csv")
    assert name == "double_pendulum-angle.csv"
    rows = list(csv.reader(io.StringIO(data.decode())))
    assert rows[0][0] == "t [s]" and len(rows[0]) == 5
    assert all("[rad]" in h for h in rows[0][1:]), rows[0]
    table = np.array([[float(v) if v else np.nan for v in row] for row in rows[1:]])
    latest = K(page, "K.runs[0].results")
    t = np.array(latest["t"])
    assert table.shape[0] == len(t)
    assert np.allclose(table[:, 0], t, rtol=0, atol=1e-12)
    probe1 = next(s for s in latest["signals"] if s["name"] == "probe1.angle")
    column = rows[0].index(next(h for h in rows[0] if h.startswith("probe1") and "run 2" in h))
    assert np.allclose(table[:, column], np.array(probe1["values"], float).ravel(), rtol=1e-12,
                       atol=1e-15)

    name, data = download(page, "plot-angle-svg")
    assert name.endswith(".svg")
    svg = ET.fromstring(data)
    ns = "{http://www.w3.org/2000/svg}"
    texts = [t.text or "" for t in svg.iter(f"{ns}text")]
    assert any(t.startswith("angle") for t in texts)
    assert sum("spring.c = 5" in t for t in texts) == 2, texts
    curves = [p for p in svg.iter(f"{ns}path") if p.get("clip-path")]
    assert len(curves) == 4 and all(p.get("d").count("L") > 500 for p in curves)

    name, data = download(page, "plot-angle-png")
    assert name.endswith(".png") and data[:8] == b"\x89PNG\r\n\x1a\n"
    from PIL import Image
    picture = Image.open(io.BytesIO(data))
    small = page.locator(f'{tid("plot-angle")} canvas').bounding_box()
    assert picture.size[0] >= small["width"] and picture.size[1] > small["height"]

    page.click(tid("plot-angle-enlarge"))
    page.wait_for_selector(tid("bigplot-angle"))
    big = page.locator(f'{tid("bigplot-angle")} canvas').bounding_box()
    assert big["width"] > 1.8 * small["width"] and big["height"] > 2 * small["height"]
    page.wait_for_function("() => window.__kinetwork.plotAxes['big:angle'] !== undefined")
    wrong, axes = plot_axes_wrong(page, "big:")
    assert not wrong, wrong
    assert len(axes["big:angle"]["y"]["ticks"]) >= 5
    page.keyboard.press("Escape")
    page.wait_for_selector(tid("plot-dialog"), state="detached")
    assert not page.errors, page.errors
