"""The studio's layout and diagrams in the browser (issue 29 items 3 and 4): an icon of its own
for every component type, and a page that fits at the window sizes people use.

Everything here is read from the rendered page (element rectangles, SVG attributes), with
real mouse events where the user would act."""

import csv
import io
import json
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from tests.studio.helpers import (K, center, misplaced, open_studio, run, screenshot, select,
                                  set_field, tid)

SEED = "models/double_pendulum.json"
SIZES = [(1000, 700), (1400, 900), (1920, 1080)]


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
    assert {"bar", "palette", "diagram", "plots", "viewer", "side"} <= set(places["panes"])
    viewer_buttons = places["controls"]["viewer"]
    assert len(viewer_buttons) >= 5, viewer_buttons            # play, time, speed, frames, view
    if width >= 1400:       # the 3-D view's bar in one row (its "view" button wrapped at 1400)
        rows = page.evaluate("() => [...document.querySelector('.kn-viewer-bar').children]"
                             ".map(e => Math.round(e.getBoundingClientRect().top + "
                             "e.getBoundingClientRect().height / 2))")
        assert max(rows) - min(rows) <= 4, rows
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
    wrong = [f"the seed run: {w}" for w in wrong]
    if width < 1920:
        wrong += every_view_whole(page, width, height, wrong)
    assert not wrong, "\n".join(wrong)
    assert not page.errors, page.errors


#: a file name longer than the bar has room for beside the name of the model
LONG = "models/my_very_long_model_name_for_the_arm.json"
#: a value whose problem is a long message
UNKNOWN = "spring_constant_of_the_shoulder_that_nobody_defined * 2"


def whole(page, what, wrong):
    """What is misplaced or cut (``misplaced``) while ``what`` is on screen, added to
    ``wrong`` (where it is not already); the panes' rectangles and controls."""
    found, places = misplaced(page)
    wrong += [f"{what}: {w}" for w in found if not any(seen.endswith(f": {w}") for seen in wrong)]
    return places


def every_view_whole(page, width, height, seen):
    """What the user opens over the seed, each in turn whole and in the window: a palette
    type's card, the Open dialog, the larger plot, the signals' list, the right-click menu,
    the JSON view, the Analysis tab's forms, a long problem, the Save as prompt, a long file
    name with unsaved changes, New asking about them, and the page with the side panel and
    the 3-D view collapsed: the list of what is wrong, beyond what is already ``seen``."""
    wrong = list(seen)
    page.hover(tid("palette-multibody.BodyShape"))    # a long card: doc, ports, 12 parameters
    page.wait_for_selector(f'{tid("palette-info")} .kn-typeinfo-params')
    whole(page, "the palette's card of BodyShape", wrong)
    page.click(tid("open"))
    page.wait_for_selector(tid(f"file-{SEED}"))
    whole(page, "the Open dialog", wrong)
    page.keyboard.press("Escape")
    page.wait_for_selector(tid("open-dialog"), state="detached")
    page.click(tid("plot-angle-enlarge"))
    page.wait_for_function("() => window.__kinetwork.plotAxes['big:angle'] !== undefined")
    whole(page, "the larger plot", wrong)
    page.keyboard.press("Escape")
    page.wait_for_selector(tid("plot-dialog"), state="detached")
    if page.locator(tid("plot-signals")).count():       # the chips folded: their list
        page.click(tid("plot-signals"))
        page.wait_for_selector(tid("plot-signals-list"))
        whole(page, "the signals' list", wrong)
        # its chips work as in a row: a signal hidden, and shown again
        chip = f'{tid("plot-signals-list")} {tid("plot-toggle-probe1.angle")}'
        page.click(chip)
        page.wait_for_selector(f'{tid("plot-signals")}:text("signals 7/8")')
        page.click(chip)
        page.wait_for_selector(f'{tid("plot-signals")}:text("signals 8/8")')
        page.click(tid("plot-signals"))
        page.wait_for_selector(tid("plot-signals-list"), state="detached")
        # a press anywhere else closes it too
        page.click(tid("plot-signals"))
        page.wait_for_selector(tid("plot-signals-list"))
        page.click(f'{tid("plots")} .kn-panel-title-inline')
        page.wait_for_selector(tid("plot-signals-list"), state="detached")
    x, y = center(page, tid("node-mass2"))
    page.mouse.click(x, y, button="right")
    page.wait_for_selector(tid("context-menu"))
    whole(page, "the right-click menu", wrong)
    page.keyboard.press("Escape")
    page.wait_for_selector(tid("context-menu"), state="detached")
    # and a press on the diagram outside it: closed, nothing else done
    page.mouse.click(x, y, button="right")
    page.wait_for_selector(tid("context-menu"))
    box = page.locator(tid("canvas")).bounding_box()
    page.mouse.click(box["x"] + 12, box["y"] + box["height"] - 12)
    page.wait_for_selector(tid("context-menu"), state="detached")
    page.click(tid("tab-json"))
    page.wait_for_selector(tid("json-text"))
    whole(page, "the JSON view", wrong)
    page.click(tid("tab-analysis"))
    page.wait_for_selector(tid("linearize-form"))
    whole(page, "the Analysis tab", wrong)
    page.click(tid("sweep-kind-random"))
    page.wait_for_selector(tid("sweep-dist-0"))
    whole(page, "the Analysis tab, a random sweep", wrong)
    page.click(tid("tab-params"))
    select(page, "spring")
    set_field(page, "param-c", UNKNOWN)
    page.wait_for_selector(f'{tid("problems")}:not([data-count="0"])')
    whole(page, "a long problem", wrong)
    page.click(tid("save-as"))
    page.wait_for_selector(tid("save-path"))
    whole(page, "the Save as prompt", wrong)
    set_field(page, "save-path", LONG)
    page.wait_for_function(f"() => window.__kinetwork.file.path === {json.dumps(LONG)}")
    set_field(page, "param-c", "2")
    page.wait_for_selector(tid("dirty"))
    page.wait_for_selector(f'{tid("problems")}[data-count="0"]')
    bar = whole(page, "a long file name, unsaved", wrong)["panes"]["bar"]
    title = page.get_attribute(tid("file"), "title")
    if not (LONG in title and "double_pendulum" in title and "unsaved" in title):
        wrong.append(f"the file's title {title!r} lacks its path, name or state")
    for part in (f'{tid("file")} b', tid("dirty")):     # the name and the mark whole, in the bar
        box = page.locator(part).bounding_box()
        if not bar["x0"] <= box["x"] <= box["x"] + box["width"] <= bar["x1"]:
            wrong.append(f"{part} at {box} outside the bar {bar}")
    if page.evaluate("() => { const b = document.querySelector('[data-testid=file] b');"
                     " return b.scrollWidth > b.clientWidth && b.clientWidth > 0; }"):
        wrong.append("the model's name is elided beside its path")
    page.click(tid("new"))                          # unsaved changes: the page asks
    page.wait_for_selector(tid("confirm-discard"))
    whole(page, "New asking about unsaved changes", wrong)
    page.click(tid("choice-cancel"))
    page.wait_for_selector(tid("confirm-discard"), state="detached")
    page.click(tid("toggle-side"))
    page.wait_for_selector(".kn-right", state="detached")
    page.click(tid("toggle-viewer"))
    page.wait_for_selector(tid("viewer"), state="detached")
    whole(page, "the side panel and the 3-D view collapsed", wrong)
    if width >= 1400:           # the plots now as wide as the window: the chips back in a row
        page.wait_for_selector(f'{tid("plots")} .kn-chips {tid("plot-toggle-probe2.torque")}')
        assert not page.locator(tid("plot-signals")).count()
    while page.locator(tid("toast")).count():       # "saved ...": not in the docs' picture
        page.locator(tid("toast")).first.click()
    screenshot(page, f"studio-{width}x{height}-collapsed.png")
    return wrong[len(seen):]


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
