"""What people reach for (issue 29 item 5), in headless Chromium with real mouse and keyboard:
Ctrl+A, the right-click menu, paste at the pointer, palette search over names, docs and
synonyms, the model's JSON with live validation, a second signal source refused on drop,
messages in the user's words inside their block, Make subsystem from a box selection then
double-click, the run counter per model, overlaid runs named."""

import json

import kinetwork as kn
from tests.studio.helpers import (K, center, deselect, open_file, open_studio, place, run,
                                  screenshot, select, set_field, tid, wait_validated, wire)

SEED = "models/double_pendulum.json"


def names(page):
    return K(page, "K.doc.components.map(c => c.name)")


def right_click(page, selector, dx=0, dy=0):
    x, y = center(page, selector)
    page.mouse.click(x + dx, y + dy, button="right")
    page.wait_for_selector(tid("context-menu"))


def blank_spot(page):
    """A point of the diagram with no block on it (screen pixels)."""
    box = page.locator(tid("canvas")).bounding_box()
    return box["x"] + box["width"] * 0.15, box["y"] + box["height"] * 0.85


def test_ctrl_a_selects_every_block_and_delete_removes_them(page, studio):
    open_studio(page, studio, open=SEED)
    deselect(page)
    page.keyboard.press("Control+a")
    page.wait_for_function("() => window.__kinetwork.selection.length === 9")
    assert page.locator(".react-flow__node.selected").count() == 9
    page.keyboard.press("Delete")
    page.wait_for_function("() => window.__kinetwork.doc.components.length === 0")
    assert K(page, "K.doc.connections") == []
    page.keyboard.press("Control+z")
    page.wait_for_function("() => window.__kinetwork.doc.components.length === 9")
    assert not page.errors, page.errors


def test_the_right_click_menu_renames_duplicates_rotates_flips_deletes_and_opens(page, studio):
    open_studio(page, studio, open=SEED)
    right_click(page, tid("node-mass2"))
    screenshot(page, "studio-menu.png")
    items = [el.get_attribute("data-testid") for el in
             page.locator('[data-testid^="menu-"]').all()]
    assert items == ["menu-rename", "menu-duplicate", "menu-rotate", "menu-flip",
                     "menu-make-subsystem", "menu-copy", "menu-delete"]
    page.click(tid("menu-rename"))
    set_field(page, "rename-to", "tip")
    page.wait_for_selector(tid("node-tip"))
    assert ["elbow.frame_b", "tip.frame_a"] in K(page, "K.doc.connections")
    right_click(page, tid("node-tip"))
    page.click(tid("menu-duplicate"))
    page.wait_for_selector(tid("node-tip1"))
    a, b = (page.locator(tid(f"node-{n}")).bounding_box() for n in ("tip", "tip1"))
    assert abs(a["y"] - b["y"]) > a["height"] or abs(a["x"] - b["x"]) > a["width"]  # apart
    right_click(page, tid("node-tip1"))
    page.click(tid("menu-rotate"))
    page.wait_for_function("() => window.__kinetwork.doc.layout.tip1.rotation === 90")
    handle = page.locator(tid("handle-tip1-frame_a"))
    assert "top" in handle.get_attribute("class")       # frame_a turned from left to top
    right_click(page, tid("node-tip1"))
    page.click(tid("menu-flip"))                        # mirrored first, then turned: bottom
    page.wait_for_function("() => window.__kinetwork.doc.layout.tip1.flip === true")
    assert "bottom" in handle.get_attribute("class")
    page.keyboard.press("Control+z")
    page.wait_for_function("() => !window.__kinetwork.doc.layout.tip1.flip")
    assert "top" in handle.get_attribute("class")
    page.keyboard.press("Control+y")
    page.wait_for_function("() => window.__kinetwork.doc.layout.tip1.flip === true")
    right_click(page, tid("node-tip1"))
    page.click(tid("menu-delete"))
    page.wait_for_selector(tid("node-tip1"), state="detached")
    # a wire: deleted alone
    n = K(page, "K.doc.connections.length")
    edge = page.locator('[data-testid^="rf__edge-probe2.port~elbow.axis"]')
    box = edge.bounding_box()
    page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2, button="right")
    page.click(tid("menu-delete"))
    page.wait_for_function(f"() => window.__kinetwork.doc.connections.length === {n - 1}")
    # the empty diagram: select all; Escape closes the menu
    x, y = blank_spot(page)
    page.mouse.click(x, y, button="right")
    page.wait_for_selector(tid("menu-select-all"))
    page.keyboard.press("Escape")
    page.wait_for_selector(tid("context-menu"), state="detached")
    # a subsystem: Open
    open_file(page, "models/robot/arm_axes.json")
    right_click(page, tid("node-shoulder_axis"))
    page.click(tid("menu-open"))
    page.wait_for_selector(tid("crumb-1"))
    assert K(page, "K.scopes") == ["Axis"]
    assert not page.errors, page.errors


def test_a_right_drag_pans_without_opening_the_menu(page, studio):
    open_studio(page, studio, open=SEED)
    x, y = blank_spot(page)
    before = page.evaluate("() => document.querySelector('.react-flow__viewport').style.transform")
    page.mouse.move(x, y)
    page.mouse.down(button="right")
    page.mouse.move(x + 80, y - 40, steps=8)
    page.mouse.up(button="right")
    page.wait_for_function("b => document.querySelector('.react-flow__viewport')"
                           ".style.transform !== b", arg=before)
    assert page.locator(tid("context-menu")).count() == 0


def test_paste_lands_at_the_pointer(page, studio):
    open_studio(page, studio, open=SEED)
    select(page, "mass2")
    page.keyboard.press("Control+c")
    x, y = blank_spot(page)
    page.mouse.move(x, y)
    page.keyboard.press("Control+v")
    page.wait_for_selector(tid("node-mass3"))
    box = page.locator(tid("node-mass3")).bounding_box()
    # its top-left corner where the pointer was (within the 10-unit grid)
    assert abs(box["x"] - x) < 25 and abs(box["y"] - y) < 25, (box, x, y)
    # and the menu's "Paste here" where the menu was opened
    x2, y2 = x + 250, y - 60
    page.mouse.click(x2, y2, button="right")
    page.click(tid("menu-paste"))
    page.wait_for_selector(tid("node-mass4"))
    box = page.locator(tid("node-mass4")).bounding_box()
    assert abs(box["x"] - x2) < 25 and abs(box["y"] - y2) < 25
    assert not page.errors, page.errors


def palette_found(page, query):
    page.fill(tid("palette-search"), query)
    # the list drawn for this query (the palette says which query it shows)
    page.wait_for_function("q => document.querySelector('[data-testid=palette]')"
                           ".dataset.query === q", arg=query)
    return [el.get_attribute("data-testid")[len("palette-"):]
            for el in page.locator('[data-testid^="palette-"][draggable]').all()]


def test_palette_search_finds_names_docs_and_synonyms_best_first(page, studio):
    open_studio(page, studio)
    assert palette_found(page, "hinge")[0] == "multibody.Revolute"
    assert palette_found(page, "link")[:2] == ["multibody.FixedTranslation", "multibody.BodyShape"]
    assert palette_found(page, "pendulum")[0] == "multibody.Revolute"
    body = palette_found(page, "body")
    assert set(body[:5]) == {"multibody.RigidBody", "multibody.BodyShape", "multibody.BodyBox",
                             "multibody.BodyCylinder", "multibody.BodySphere"}
    assert len(body) < 30
    assert palette_found(page, "motor")[0] == "electrical.DCMotor"
    assert palette_found(page, "spring")[0].endswith(".Spring")
    assert palette_found(page, "qwertz") == []
    page.locator(tid("palette-none")).wait_for()
    # a result is placed as any palette item
    palette_found(page, "hinge")
    page.dblclick(tid("palette-multibody.Revolute"))
    page.wait_for_selector(tid("node-revolute1"))
    assert not page.errors, page.errors


def test_the_json_view_validates_as_it_is_typed_and_applies_as_one_step(page, studio):
    open_studio(page, studio, open=SEED)
    page.click(tid("tab-json"))
    text = page.locator(tid("json-text"))
    assert json.loads(text.input_value()) == K(page, "K.doc")
    model = K(page, "K.doc")
    # broken JSON: said at once, with its line, and Apply refused
    text.fill(json.dumps(model, indent=2).replace('"version": 1,', '"version": 1,,', 1))
    page.wait_for_function("() => document.querySelector('[data-testid=json-state]')"
                           ".textContent.includes('line')")
    assert page.locator(tid("json-apply")).is_disabled()
    # a model with a problem: the server's checker says which, in the user's words
    bad = json.loads(json.dumps(model))
    next(c for c in bad["components"] if c["name"] == "mass1")["params"]["mass"] = -1
    text.fill(json.dumps(bad, indent=2))
    page.locator(tid("json-problems")).filter(has_text="mass1.mass").wait_for()
    assert "components[" not in page.locator(tid("json-problems")).inner_text()
    # a good change applied: one undo step
    good = json.loads(json.dumps(model))
    good["parameters"]["c"] = 3.5
    text.fill(json.dumps(good, indent=2))
    page.wait_for_function("() => document.querySelector('[data-testid=json-state]')"
                           ".textContent === 'valid'")
    page.click(tid("json-apply"))
    page.wait_for_function("() => window.__kinetwork.doc.parameters.c === 3.5")
    assert json.loads(text.input_value())["parameters"]["c"] == 3.5
    page.locator("body").click(position={"x": 5, "y": 5})
    page.keyboard.press("Control+z")
    page.wait_for_function("() => window.__kinetwork.doc.parameters.c === 1")
    assert not page.errors, page.errors


def test_a_second_source_on_a_signal_is_refused_on_drop_with_the_reason(page, studio):
    open_studio(page, studio)
    place(page, "signals.Sine", "sine", 80, 120)
    place(page, "signals.Step", "step", 80, 300)
    place(page, "signals.Gain", "gain", 400, 200)
    wire(page, "sine.y", "gain.u")
    page.wait_for_function("() => window.__kinetwork.doc.connections.length === 1")
    wire(page, "sine.y", "step.y")                 # output to output
    toast = page.locator(tid("toast")).filter(has_text="both are signal outputs")
    toast.wait_for()
    assert "cannot connect sine.y to step.y" in toast.inner_text()
    wire(page, "step.y", "gain.u")                 # an input fed already
    page.locator(tid("toast")).filter(has_text="fed by sine.y already").wait_for()
    assert K(page, "K.doc.connections") == [["sine.y", "gain.u"]]
    assert not page.errors, page.errors


def test_a_problem_is_said_in_the_users_words_inside_its_block(page, studio):
    open_studio(page, studio, open=SEED)
    select(page, "mass1")
    set_field(page, "param-mass", "-1")
    message = page.locator(tid("node-msg-mass1"))
    message.wait_for()
    assert message.inner_text().startswith("mass: must be >= 0")
    problems = page.locator(tid("problems")).inner_text()
    assert "mass1.mass\nmust be >= 0" in problems and "components[" not in problems
    field = page.locator(".kn-param.bad .kn-param-problem").inner_text()
    assert field.startswith("mass1.mass: must be >= 0")
    # inside the block: it covers no other block
    block = page.locator(tid("node-mass1")).bounding_box()
    msg = message.bounding_box()
    assert block["x"] <= msg["x"] and msg["x"] + msg["width"] <= block["x"] + block["width"]
    assert block["y"] <= msg["y"] and msg["y"] + msg["height"] <= block["y"] + block["height"]
    assert not page.errors, page.errors


def test_make_subsystem_from_a_box_selection_then_double_click_opens_it(page, studio):
    open_studio(page, studio, open=SEED)
    deselect(page)
    boxes = [page.locator(tid(f"node-{n}")).bounding_box() for n in ("elbow", "mass2", "probe2")]
    x0 = min(b["x"] for b in boxes) - 12
    y0 = min(b["y"] for b in boxes) - 12
    x1 = max(b["x"] + b["width"] for b in boxes) + 12
    y1 = max(b["y"] + b["height"] for b in boxes) + 12
    page.mouse.move(x0, y0)
    page.mouse.down()
    page.mouse.move(x1, y1, steps=10)
    page.mouse.up()
    page.wait_for_function("() => window.__kinetwork.selection.length === 3")
    page.click(tid("make-subsystem"))
    set_field(page, "subsystem-name", "Forearm")
    page.wait_for_selector(tid("node-forearm1"))
    page.locator(f'{tid("node-forearm1")} .kn-block-name').dblclick()
    page.wait_for_selector(tid("crumb-1"))
    assert K(page, "K.scopes") == ["Forearm"]
    for inner in ("elbow", "mass2", "probe2"):
        page.wait_for_selector(tid(f"node-{inner}"))
    assert not page.errors, page.errors


def test_runs_are_counted_per_model_and_overlaid_runs_are_named(page, studio):
    open_studio(page, studio, open=SEED)
    deselect(page)
    set_field(page, "sim-t_end", "1")
    assert run(page) == "done"
    select(page, "spring")
    set_field(page, "param-c", "5")
    assert run(page) == "done"
    deselect(page)
    set_field(page, "mparam-d", "0.2")
    assert run(page) == "done"
    labels = K(page, "K.runs.map(r => r.label)")
    assert labels == ["run 3 · d = 0.2", "run 2 · spring.c = 5", "run 1"]
    header = page.locator(tid("plot-runs")).inner_text()
    assert "run 3 · d = 0.2" in header and "run 2 · spring.c = 5" in header
    legend = page.locator(f'{tid("plot-angle")} .u-legend').inner_text()
    assert "run 3 · d = 0.2" in legend
    # another model: its runs count from 1
    open_file(page, "models/fourbar.json")
    assert run(page) == "done"
    assert K(page, "K.runs.map(r => r.n)") == [1]
    assert page.locator(tid("plot-runs")).inner_text().startswith("run 1")
    assert not page.errors, page.errors


def test_a_built_model_keeps_its_parameters_through_the_json_view(page, studio):
    """The text view and the diagram are one model: what the diagram built, the text shows,
    and kn reads it as the same model."""
    open_studio(page, studio)
    place(page, "multibody.Ground", "ground", 80, 120)
    place(page, "multibody.Revolute", "joint", 300, 120)
    wire(page, "ground.frame", "joint.frame_a")
    page.wait_for_function("() => window.__kinetwork.doc.connections.length === 1")
    wait_validated(page)
    page.click(tid("tab-json"))
    model = json.loads(page.locator(tid("json-text")).input_value())
    built = kn.loads(json.dumps(model), validate=False)
    assert set(built.components) == {"ground", "joint"}
    assert not page.errors, page.errors
