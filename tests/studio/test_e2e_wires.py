"""Readable diagrams in the browser (issue 29 item 4): wires routed orthogonally, never on a
track of another net and never through a block, the examples fitted at a zoom of at least
0.5 in a 1400x900 window, and the same after a block is dragged with the mouse.

Everything is read from the rendered page: the SVG paths of the wires, the blocks' boxes
(React Flow's node elements, in the diagram's own coordinates) and the viewport's zoom. The
nets (which wires may share a track) come from the model's connections, as a reader of the
file would group them, not from the page's router. One page serves the whole module."""

import json
import os
import pathlib
import re
import shutil

import networkx as nx
import pytest
from browser import browser_missing

from tests.studio.conftest import E2E_TOKEN, REPO, Studio, _why_not, npm_installed
from tests.studio.helpers import (K, open_in_page, open_studio, screenshot, serving, set_field,
                                  tid, wait_validated)

SIZE = {"width": 1400, "height": 900}
TOL = 1.0            # px: collinear within it, and overlapping by more than it, is one track
MIN_ZOOM = 0.5

#: the wires (path data and the two ports each joins) and the blocks' boxes, from the DOM
DRAWN = """() => {
    const wires = [...document.querySelectorAll('.react-flow__edge')].map((g) => ({
        id: g.getAttribute('data-id') || g.getAttribute('data-testid') || '',
        d: g.querySelector('.react-flow__edge-path').getAttribute('d')}));
    const blocks = [...document.querySelectorAll('.react-flow__node')].map((el) => {
        const m = /translate\\(\\s*([-\\d.e]+)px\\s*,\\s*([-\\d.e]+)px/.exec(el.style.transform);
        return {id: el.getAttribute('data-id'), x: +m[1], y: +m[2],
                w: el.offsetWidth, h: el.offsetHeight};
    });
    const m = new DOMMatrix(getComputedStyle(document.querySelector('.react-flow__viewport')).transform);
    const r = document.querySelector('.react-flow').getBoundingClientRect();
    return {wires, blocks, zoom: m.a, tx: m.e, ty: m.f,
            pane: {x: r.left, y: r.top, w: r.width, h: r.height}};
}"""


def polyline(d):
    """The points of an SVG path made of M, L, H and V commands (absolute); a curve fails."""
    tokens = re.findall(r"[A-Za-z]|-?[\d.]+(?:e-?\d+)?", d)
    points, cmd, i = [], None, 0
    while i < len(tokens):
        if tokens[i].isalpha():
            cmd = tokens[i]
            i += 1
            continue
        assert cmd in "MLHV", f"the wire {d!r} is not made of straight segments"
        x, y = points[-1] if points else (0.0, 0.0)
        if cmd in "ML":
            x, y = float(tokens[i]), float(tokens[i + 1])
            i += 2
        elif cmd == "H":
            x = float(tokens[i])
            i += 1
        else:
            y = float(tokens[i])
            i += 1
        points.append((x, y))
    return points


def nets_of(doc):
    """Net number of each port ("comp.port"), from the model's connections."""
    g = nx.Graph()
    g.add_edges_from((str(a), str(b)) for a, b in doc.get("connections", []))
    return {p: i for i, comp in enumerate(nx.connected_components(g)) for p in comp}


def faults(page):
    """What a reader sees wrong in the diagram on screen: segments that are not horizontal
    or vertical, pairs of segments of different nets on one track, segments whose inside
    passes through a block's box, wires whose ends are not at their blocks; and the zoom."""
    doc = K(page, "K.doc")
    net = nets_of(doc)
    drawn = page.evaluate(DRAWN)
    boxes = {b["id"]: b for b in drawn["blocks"]}
    segs, slanted, loose = [], [], []
    for w in drawn["wires"]:
        a, b, _ = w["id"].split("~")
        pts = polyline(w["d"])
        for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
            if abs(x0 - x1) > TOL and abs(y0 - y1) > TOL:
                slanted.append(w["id"])
            segs.append((net[a], (x0, y0), (x1, y1), w["id"]))
        for end, ref in ((pts[0], a), (pts[-1], b)):
            box = boxes[ref.split(".")[0]]
            gap = max(box["x"] - end[0], end[0] - box["x"] - box["w"],
                      box["y"] - end[1], end[1] - box["y"] - box["h"])
            if not -TOL <= gap <= 10:
                loose.append(f"{w['id']} ends {gap:.0f} px from {ref}")
    shared = []
    for i, (n1, p1, q1, id1) in enumerate(segs):
        for n2, p2, q2, id2 in segs[i + 1:]:
            if n1 == n2:
                continue
            for u in (0, 1):
                v = 1 - u
                if max(abs(p1[u] - q1[u]), abs(p2[u] - q2[u]), abs(p1[u] - p2[u])) > TOL:
                    continue
                lo = max(min(p1[v], q1[v]), min(p2[v], q2[v]))
                hi = min(max(p1[v], q1[v]), max(p2[v], q2[v]))
                if hi - lo > TOL:
                    shared.append(f"{id1} / {id2}")
    through = []
    for _, p, q, wid in segs:
        for b in drawn["blocks"]:
            if (max(p[0], q[0]) > b["x"] + TOL and min(p[0], q[0]) < b["x"] + b["w"] - TOL
                    and max(p[1], q[1]) > b["y"] + TOL and min(p[1], q[1]) < b["y"] + b["h"] - TOL):
                through.append(f"{wid} through {b['id']}")
    return {"slanted": slanted, "shared": shared, "through": through, "loose": loose,
            "zoom": drawn["zoom"], "wires": len(drawn["wires"]), "segments": len(segs)}


#: what is drawn of the diagram that lies outside the diagram's pane, from rendered boxes
OUTSIDE = """() => {
    const p = document.querySelector('.react-flow').getBoundingClientRect();
    const parts = [...document.querySelectorAll('.react-flow__edge-path, .react-flow__node, ' +
        '.react-flow__node .kn-port, .react-flow__node .kn-port-label, .kn-extport')];
    return parts.map((el) => {
        const b = el.getBoundingClientRect();
        const what = el.closest('.react-flow__edge, .react-flow__node');
        return {what: `${el.getAttribute('class').split(' ')[0]} of ${what && what.getAttribute('data-id')}`,
                out: Math.max(p.left - b.left, p.top - b.top, b.right - p.right, b.bottom - p.bottom)};
    }).filter((x) => x.out > 0.5);
}"""


def assert_fitted_whole(page, what):
    """The fitted view holds every wire's path, every block and every port and port name
    (read from their rendered boxes), not only the blocks: a wire routed round the top block
    was cut by the pane's edge."""
    out = page.evaluate(OUTSIDE)
    assert not out, f"{what}: {len(out)} parts outside the pane at fit: " \
                    f"{[(x['what'], round(x['out'], 1)) for x in out[:6]]}"


def assert_readable(found, what, fit=True):
    assert found["wires"] > 0, f"{what}: no wire drawn"
    assert not found["slanted"], f"{what}: wires not orthogonal: {found['slanted'][:5]}"
    assert not found["shared"], f"{what}: {len(found['shared'])} pairs of segments of " \
                                f"different nets on one track: {found['shared'][:5]}"
    assert not found["through"], f"{what}: {len(found['through'])} segments through blocks: " \
                                 f"{found['through'][:5]}"
    assert not found["loose"], f"{what}: wires away from their ports: {found['loose'][:5]}"
    if fit:
        assert found["zoom"] >= MIN_ZOOM, f"{what}: fits only at zoom {found['zoom']:.2f}"


@pytest.fixture(scope="module")
def site(tmp_path_factory, test_page):
    """The studio over a copy of models/ and a 32-link chain, for the whole module."""
    from kinetwork.studio.server import create_app
    from scenes.chains import chain

    root = tmp_path_factory.mktemp("wires")
    shutil.copytree(REPO / "models", root / "models")
    chain(32).save(root / "chain32.json")
    with serving(create_app(root, E2E_TOKEN, static=test_page)) as port:
        yield Studio(root, port)


@pytest.fixture(scope="module")
def screen(chromium, site):
    """One page at 1400x900 for the module."""
    why = _why_not()
    if why:
        browser_missing(why)
    context = chromium.new_context(viewport=SIZE)
    pg = context.new_page()
    pg.errors = []
    pg.on("pageerror", lambda e: pg.errors.append(f"uncaught: {e}"))
    pg.set_default_timeout(60_000)
    open_studio(pg, site)
    yield pg
    context.close()


def show(page, site, **query):
    """Open a model (an example by name, or a file of the studio's folder) through the Open
    dialog of the page already loaded, and wait until it is drawn, fitted and its wires are
    routed."""
    open_in_page(page, **query)
    settle(page)


def settle(page):
    """Wait until the diagram shown is drawn, its wires routed, and fitted (wires included)
    to the pane as it is now; then until nothing moves on two frames."""
    page.wait_for_function("() => document.querySelectorAll('.react-flow__edge-path').length > 0")
    wait_routed(page)
    page.wait_for_function("() => window.__kinetwork.fitted")
    page.wait_for_function("""() => new Promise((done) => {
        const z = () => document.querySelector('.react-flow__viewport').style.transform;
        const a = z(); requestAnimationFrame(() => requestAnimationFrame(() => done(a === z())));
    })""")
    wait_routed(page)


def wait_routed(page):
    """Wait until the wires drawn are the routing worker's answer for the diagram as shown,
    and drawn (the routes arrive between frames)."""
    page.wait_for_function("() => window.__kinetwork.routed")
    page.wait_for_function("() => new Promise((done) => requestAnimationFrame(() => "
                           "requestAnimationFrame(() => done(window.__kinetwork.routed))))")


def examples():
    from kinetwork.studio import files
    return sorted(files.examples())


@pytest.mark.parametrize("name", examples())
def test_every_example_readable_at_1400x900(screen, site, name):
    """Each example opens valid (no problem listed, no error on the page), fitted at a zoom
    of at least 0.5, its wires orthogonal, on no other net's track, through no block, and
    ending at their ports (the examples run from the page are test_e2e's)."""
    show(screen, site, example=name)
    wait_validated(screen)
    assert K(screen, "K.validation.ok"), (name, K(screen, "K.validation.problems"))
    if os.environ.get("KINETWORK_E2E_SHOTS"):
        stem = os.path.join(os.environ["KINETWORK_E2E_SHOTS"], name.replace("/", "-"))
        screen.screenshot(path=f"{stem}.png")
        pathlib.Path(f"{stem}.json").write_text(json.dumps(K(screen, "K.wires")))
    assert_readable(faults(screen), name)
    assert_fitted_whole(screen, name)
    assert not screen.errors, screen.errors


def test_chain_of_32_links_wraps_into_rows(screen, site):
    """A 32-link chain (97 blocks) wraps into rows instead of one row beyond the minimum zoom
    (0.1): it fits at 0.3 or more, its wires as readable as any model's. (At 0.5 it would
    have to be folded into subsystems of links, which the studio does not do by itself.)"""
    show(screen, site, open="chain32.json")
    found = faults(screen)
    assert_readable(found, "chain32", fit=False)
    assert found["zoom"] >= 0.3, found["zoom"]
    rows = sorted({round(b["y"] / 150) for b in screen.evaluate(DRAWN)["blocks"]})
    assert len(rows) >= 4, rows


def test_chain_of_32_links_folded_reads_at_half_zoom(screen, site):
    """The studio offers to fold the 32 alike links (joint, body, translation) into
    subsystems; with the mouse: Fold, the definition's name, Enter. The diagram then shows
    the ground and 32 instances of the new definition, fitted at a zoom of at least 0.5 in
    a 1400x900 window, its wires as readable as any model's; the folded document is valid,
    and Undo brings the flat chain back."""
    show(screen, site, open="chain32.json")
    assert faults(screen)["zoom"] < MIN_ZOOM      # the flat chain cannot be read whole
    screen.locator(tid("fold-offer")).wait_for()
    screen.locator(tid("fold-accept")).click()
    set_field(screen, "fold-name", "Link")
    screen.wait_for_function("() => window.__kinetwork.doc.components.length === 33")
    screen.wait_for_selector(tid("node-link31"))
    settle(screen)
    doc = K(screen, "K.doc")
    assert [c["type"] for c in doc["components"]].count("Link") == 32
    assert sorted(doc["definitions"]["Link"]["ports"]) == ["frame_a", "frame_b"]
    screenshot(screen, "studio-chain32-folded-1400x900.png")
    assert_readable(faults(screen), "chain32 folded")
    assert not screen.locator(tid("fold-offer")).count()
    screen.wait_for_function("() => window.__kinetwork.validated")
    assert K(screen, "K.validation.ok"), K(screen, "K.validation.problems")
    screen.keyboard.press("Control+z")
    screen.wait_for_function("() => window.__kinetwork.doc.components.length === 97")
    assert not screen.errors, screen.errors


def free_spot(page, name):
    """Where block ``name`` can go in the part of the diagram on screen, clear of every other
    block by 40 px and of the pane's edges and controls, about 400 px (of the diagram) from
    where it is: the move (dx, dy) in screen pixels."""
    d = page.evaluate(DRAWN)
    z, pane = d["zoom"], d["pane"]
    me = next(b for b in d["blocks"] if b["id"] == name)
    others = [b for b in d["blocks"] if b["id"] != name]
    # away from the pane's edges (where a drag pans the view) and the corners that hold the
    # zoom buttons (left) and the minimap (right)
    x0, x1 = (80 - d["tx"]) / z, (pane["w"] - 80 - d["tx"]) / z - me["w"]
    y0, y1 = (60 - d["ty"]) / z, (pane["h"] - 120 - d["ty"]) / z - me["h"]
    best = None
    for i in range(41):
        for j in range(41):
            x, y = x0 + (x1 - x0) * i / 40, y0 + (y1 - y0) * j / 40
            if any(x < b["x"] + b["w"] + 40 and b["x"] < x + me["w"] + 40 and
                   y < b["y"] + b["h"] + 40 and b["y"] < y + me["h"] + 40 for b in others):
                continue
            # a move across the neighbours, not to the far edge of the pane
            off = abs(abs(x - me["x"]) + abs(y - me["y"]) - 400)
            if best is None or off < best[0]:
                best = (off, x, y)
    assert best, f"no free room for {name} on screen"
    return (best[1] - me["x"]) * z, (best[2] - me["y"]) * z


def drag_block(page, name):
    """Drag block ``name`` with the mouse, by its name (not a port), to a free place about
    400 px away; waits until the model holds its new place."""
    dx, dy = free_spot(page, name)
    before = K(page, f"K.doc.layout && K.doc.layout[{json.dumps(name)}]")
    box = page.locator(f"{tid(f'node-{name}')} .kn-block-name").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    for k in range(1, 11):
        page.mouse.move(x + dx * k / 10, y + dy * k / 10)
    page.mouse.up()
    page.wait_for_function(f"() => JSON.stringify(window.__kinetwork.doc.layout[{json.dumps(name)}])"
                           f" !== {json.dumps(json.dumps(before))}")


@pytest.mark.parametrize("model, block", [
    ({"open": "models/double_pendulum.json"}, "elbow"),
    ({"example": "arm_computed_torque"}, None),
    ({"example": "robot_r3/FullRobot"}, None),
    ({"open": "chain32.json"}, None),
])
def test_wires_rerouted_when_a_block_is_dragged(screen, site, model, block):
    """A block dragged with the mouse across its neighbours to a free place: its wires follow
    it and every wire still keeps off other nets' tracks and out of blocks."""
    show(screen, site, **model)
    names = [c["name"] for c in K(screen, "K.doc.components")]
    name = block or names[len(names) // 2]
    assert_readable(faults(screen), f"{model} before the drag", fit="chain32.json" not in model.values())
    drag_block(screen, name)
    wait_routed(screen)
    drawn = screen.evaluate(DRAWN)["blocks"]
    me = next(b for b in drawn if b["id"] == name)
    assert not [b["id"] for b in drawn if b is not me and b["x"] < me["x"] + me["w"] and
                me["x"] < b["x"] + b["w"] and b["y"] < me["y"] + me["h"] and
                me["y"] < b["y"] + b["h"]], "the block was dropped on another"
    assert_readable(faults(screen), f"{model} after dragging {name}", fit=False)
    assert not screen.errors, screen.errors


#: the window sizes a diagram must read at: one page resized to each
SIZES = [(1000, 700), (1400, 900), (1920, 1080)]


def at_sizes(page):
    """Resize ``page`` to each of SIZES in turn (yielding the size), the diagram refitted to
    it; back to SIZE at the end."""
    try:
        for w, h in SIZES:
            page.set_viewport_size({"width": w, "height": h})
            settle(page)
            yield w, h
    finally:
        page.set_viewport_size(SIZE)
        settle(page)


@pytest.mark.parametrize("model", ["double_pendulum", "arm_computed_torque"])
def test_screenshots(screen, site, model):
    """The seed and arm_computed_torque at the three window sizes, for the docs: opened
    once, the window resized (the view refits itself, as on opening at that size)."""
    show(screen, site, example=model)
    for w, h in at_sizes(screen):
        screenshot(screen, f"studio-diagram-{model}-{w}x{h}.png")
        assert_readable(faults(screen), f"{model} at {w}x{h}", fit=False)
        assert_fitted_whole(screen, f"{model} at {w}x{h}")


def test_page_answers_while_wires_are_routed(screen, site):
    """Routing runs in a web worker: with its answer outstanding (held back through the test
    hook, so that the machine's speed does not matter) a block dragged with the mouse drops,
    a click on another block selects it, the wires not touching the dragged block keep their
    routes on screen; released, the worker's routes are drawn and as readable as before."""
    show(screen, site, open="chain32.json")
    assert K(screen, "K.wires.where") == "worker"
    names = [c["name"] for c in K(screen, "K.doc.components")]
    name, other = names[len(names) // 2], names[3]
    paths = "() => Object.fromEntries([...document.querySelectorAll('.react-flow__edge')].map(" \
            "(g) => [g.getAttribute('data-id'), g.querySelector('.react-flow__edge-path')" \
            ".getAttribute('d')]))"
    before = screen.evaluate(paths)
    K(screen, "K.holdRouting(true)")
    try:
        drag_block(screen, name)
        assert not K(screen, "K.routed")
        screen.evaluate("() => document.addEventListener('click', (e) => { window.__clicked ="
                        " [e.timeStamp, performance.now()]; }, {once: true, capture: true})")
        box = screen.locator(f"{tid(f'node-{other}')} .kn-block-name").bounding_box()
        screen.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        screen.wait_for_function(f"() => window.__kinetwork.selection.includes({json.dumps(other)})")
        assert not K(screen, "K.routed"), "the routes arrived before the click was answered"
        now = screen.evaluate(paths)
        away = [w for w in before if name not in {end.split(".")[0] for end in w.split("~")[:2]}]
        assert away and all(now[w] == before[w] for w in away)
        waited = screen.evaluate("() => window.__clicked[1] - window.__clicked[0]")
        print(f"click taken {waited:.0f} ms after the event, with the routing outstanding")
    finally:
        K(screen, "K.holdRouting(false)")
    wait_routed(screen)
    assert K(screen, "K.wires.where") == "worker"
    assert_readable(faults(screen), "chain32 after the held drag", fit=False)
    assert not screen.errors, screen.errors
