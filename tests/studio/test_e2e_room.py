"""Large diagrams leave room to read them (issue 29 item 4): at fit zoom nothing covers a
block, at 1000x700, 1400x900 and 1920x1080, for a 32-link chain (flat, then folded with the
mouse) and the largest examples: the zoom and fit buttons sit in the bar above the diagram,
the minimap shows by itself only where it covers no block (the "map" button shows it on
demand), the offer to fold a repeated chain is a bar above the diagram; the fit button does
the same as opening; a subsystem's block is as wide as its ports' names need; the bars and
panes around the diagram whole at every size (helpers.misplaced). Everything is
read from the rendered boxes (getBoundingClientRect) on one page for the module."""

from tests.studio.helpers import K, misplaced, screenshot, set_field, tid
from tests.studio.test_e2e_wires import (DRAWN, SIZES, assert_fitted_whole, at_sizes,  # noqa: F401
                                         polyline, screen, settle, show, site)

#: the blocks' boxes and those of whatever may lie over the diagram, in page pixels
BOXES = """() => {
    const box = (el) => { const b = el.getBoundingClientRect();
        return {x: b.left, y: b.top, w: b.width, h: b.height}; };
    return {
        blocks: [...document.querySelectorAll('.react-flow__node')].map((el) =>
            ({id: el.getAttribute('data-id'), ...box(el)})),
        over: [...document.querySelectorAll('.react-flow__panel, .kn-fold-offer, .kn-offer, ' +
                                            '.kn-view-tools')].map((el) =>
            ({what: ['react-flow__minimap', 'react-flow__panel', 'kn-fold-offer', 'kn-offer',
                     'kn-view-tools'].find((c) => el.classList.contains(c)), ...box(el)})),
        pane: box(document.querySelector('.react-flow')),
    };
}"""


#: the diagram's zoom
ZOOM = "() => new DOMMatrix(getComputedStyle(document.querySelector('.react-flow__viewport'))" \
       ".transform).a"


def covered(page):
    """What covers a block (and the minimap over a wire), and the blocks not wholly in the
    diagram's pane."""
    d = page.evaluate(BOXES)
    p = d["pane"]
    hits = [f"{o['what']} over {b['id']}" for o in d["over"] for b in d["blocks"]
            if o["w"] and o["h"] and b["x"] < o["x"] + o["w"] and o["x"] < b["x"] + b["w"]
            and b["y"] < o["y"] + o["h"] and o["y"] < b["y"] + b["h"]]
    # the minimap, shown by itself, hides no wire either (the user's minimap may)
    drawn = page.evaluate(DRAWN)
    z, tx, ty, q = drawn["zoom"], drawn["tx"], drawn["ty"], drawn["pane"]
    for o in d["over"]:
        if o["what"] != "react-flow__minimap" or not o["w"] or not o["h"]:
            continue
        for w in drawn["wires"]:
            pts = [(q["x"] + tx + x * z, q["y"] + ty + y * z) for x, y in polyline(w["d"])]
            if any(min(a[0], b[0]) < o["x"] + o["w"] and o["x"] < max(a[0], b[0])
                   and min(a[1], b[1]) < o["y"] + o["h"] and o["y"] < max(a[1], b[1])
                   for a, b in zip(pts, pts[1:])):
                hits.append(f"minimap over the wire {w['id']}")
    out = [b["id"] for b in d["blocks"] if b["x"] < p["x"] - 0.5 or b["y"] < p["y"] - 0.5
           or b["x"] + b["w"] > p["x"] + p["w"] + 0.5 or b["y"] + b["h"] > p["y"] + p["h"] + 0.5]
    return hits, out, {o["what"] for o in d["over"]}


def assert_clear(page, what):
    assert_fitted_whole(page, what)
    hits, out, over = covered(page)
    assert not hits, f"{what}: {len(hits)} blocks covered: {hits[:6]}"
    assert not out, f"{what}: blocks outside the pane at fit zoom: {out[:6]}"
    wrong, _ = misplaced(page)                  # the fold bar, the bars and panes whole
    assert not wrong, f"{what}:\n" + "\n".join(wrong)
    return over


def test_nothing_covers_a_block_at_fit_zoom(screen, site):  # noqa: F811
    """At each window size (one page, resized: the view refits itself as on opening at that
    size), the 32-link chain, flat then folded with the mouse, and the largest examples."""
    show(screen, site, open="chain32.json")
    for w, h in at_sizes(screen):
        screen.locator(tid("fold-offer")).wait_for()
        over = assert_clear(screen, f"chain32 at {w}x{h}")
        screenshot(screen, f"studio-chain32-{w}x{h}.png")
        assert {"kn-fold-offer", "kn-view-tools"} <= over
        # zoomed in with the buttons, the fit button brings the whole back, clear
        before = screen.evaluate(ZOOM)
        screen.locator(tid("zoom-in")).click()
        screen.wait_for_function(f"() => ({ZOOM})() > {before}")
        screen.locator(tid("fit-view")).click()
        screen.wait_for_function(f"() => Math.abs(({ZOOM})() - {before}) < 1e-9")
        assert_clear(screen, f"chain32 fitted by the button at {w}x{h}")
        # the fold bar's button can be clicked at this size (what a click would check)
        screen.locator(tid("fold-accept")).click(trial=True)
    # folded with the mouse, in the smallest window: the bar goes, the folded chain fits
    # clear of the controls
    screen.set_viewport_size({"width": SIZES[0][0], "height": SIZES[0][1]})
    settle(screen)
    screen.locator(tid("fold-accept")).click()
    set_field(screen, "fold-name", "Link")
    screen.wait_for_function("() => window.__kinetwork.doc.components.length === 33")
    settle(screen)
    for w, h in at_sizes(screen):
        assert not screen.locator(tid("fold-offer")).count()
        assert_clear(screen, f"chain32 folded at {w}x{h}")
        screenshot(screen, f"studio-chain32-folded-{w}x{h}.png")
    for example in ("arm_computed_torque", "robot_r3/FullRobot"):
        show(screen, site, example=example)
        for w, h in at_sizes(screen):
            over = assert_clear(screen, f"{example} at {w}x{h}")
            # the minimap on demand: the button shows it (over the diagram: the user's
            # choice), and puts it away again
            toggle = screen.locator(tid("minimap-toggle"))
            for _ in range(2):
                shown = "react-flow__minimap" in over
                toggle.click()
                screen.wait_for_function(f"() => !!document.querySelector('.react-flow__minimap')"
                                         f" === {'false' if shown else 'true'}")
                over = covered(screen)[2]
            assert_clear(screen, f"{example} at {w}x{h} with the minimap as it was")
            # the user's choice kept for the rest of the session: back to the studio's own
            # (shown where it covers no block), as a new page starts, for the next size
            K(screen, "K.store.getState().setMinimap(null)")
    assert not screen.errors, screen.errors


def test_a_subsystem_block_is_as_wide_as_its_port_names(screen, site):  # noqa: F811
    """Make subsystem names the new block's ports after what they were inside
    (``link1_frame_a``): shown whole at zoom 1, none cut short with an ellipsis."""
    show(screen, site, open="models/double_pendulum.json")
    screen.locator(f'{tid("node-link1")} .kn-block-name').click()
    for name in ("elbow", "mass2"):
        screen.locator(f'{tid(f"node-{name}")} .kn-block-name').click(modifiers=["Control"])
    screen.wait_for_function("() => window.__kinetwork.selection.length === 3")
    screen.click(tid("make-subsystem"))
    set_field(screen, "subsystem-name", "Forearm")
    screen.wait_for_selector(tid("node-forearm1"))
    settle(screen)
    labels = screen.evaluate("""() => [...document.querySelectorAll(
        '[data-testid="node-forearm1"] .kn-port-label')].map((el) => {
        const b = el.getBoundingClientRect();
        return {text: el.textContent, shown: el.clientWidth, needs: el.scrollWidth,
                x: b.left, y: b.top, w: b.width, h: b.height}; })""")
    assert {x["text"] for x in labels} == {"link1_frame_a", "elbow_axis"}
    assert all(x["needs"] <= x["shown"] for x in labels), labels
    # and no name over another
    assert not [(a["text"], b["text"]) for i, a in enumerate(labels) for b in labels[i + 1:]
                if a["x"] < b["x"] + b["w"] and b["x"] < a["x"] + a["w"]
                and a["y"] < b["y"] + b["h"] and b["y"] < a["y"] + a["h"]], labels
    screen.keyboard.press("Control+z")
    screen.wait_for_selector(tid("node-elbow"))
    assert not screen.errors, screen.errors
