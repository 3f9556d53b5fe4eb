"""What the studio's end-to-end tests do with the page: real mouse and keyboard events, and
waits on the page's state (the test build's window.__kinetwork), never on time."""

import contextlib
import functools
import json
import os
import pathlib
import re
import tempfile
import threading
import time

from tests import procstat

RUN_TIMEOUT = 240_000          # ms: EngineV6 compiles for ~30 s on a busy 2-core machine
#: where the screenshots go: a folder of the test run, unless KINETWORK_SCREENSHOTS names
#: one (`KINETWORK_SCREENSHOTS=docs/images pytest tests/studio` refreshes the docs'); a test
#: run never rewrites files of the repository
IMAGES = pathlib.Path(os.environ.get("KINETWORK_SCREENSHOTS")
                      or pathlib.Path(tempfile.gettempdir()) / "kinetwork-screenshots")


@contextlib.contextmanager
def serving(app):
    """``app`` served over HTTP by uvicorn in a thread, on a free local port (a socket held
    from the start, as ``kinetwork studio`` holds it): yields the port; on the way out the
    server is asked to exit, must stop within 30 s, and its socket is closed."""
    import uvicorn

    from kinetwork.studio import launch
    sock = launch._listen(None)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", ws="none", lifespan="on"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        end = time.monotonic() + 30
        while not server.started and time.monotonic() < end:
            time.sleep(0.02)
        assert server.started, "the studio's server did not start"
        yield sock.getsockname()[1]
    finally:
        server.should_exit = True
        thread.join(30)
        sock.close()
    assert not thread.is_alive(), "the studio's server did not stop"


def screenshot(page, name):
    """The page (or one of its elements, a locator) as it is now, as ``IMAGES/name``; a picture no page of docs/ shows goes to
    ``IMAGES/unshown/``, so that refreshing the docs' folder adds nothing they do not use."""
    folder = IMAGES if name in _shown_in_docs() else IMAGES / "unshown"
    folder.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(folder / name))


@functools.cache
def _shown_in_docs():
    """The names of the pictures the pages of docs/ show (``images/NAME``)."""
    docs = pathlib.Path(__file__).resolve().parents[2] / "docs"
    return {m.group(1) for page in docs.rglob("*.md")
            for m in re.finditer(r"images/([\w.-]+\.png)", page.read_text(encoding="utf-8"))}


def tid(name):
    return f'[data-testid="{name}"]'


def K(page, expr):
    """Evaluate ``expr`` on the studio's testing hook (window.__kinetwork as K)."""
    return page.evaluate(f"() => {{ const K = window.__kinetwork; return ({expr}); }}")


def open_studio(page, studio, **query):
    """Load the page (and the model its address names, drawn); the seconds from navigation
    to the palette being ready."""
    t0 = time.perf_counter()
    page.goto(studio.url(**query))
    page.wait_for_selector(f'{tid("palette")}[data-ready="1"]')
    seconds = time.perf_counter() - t0
    if "open" in query:
        page.wait_for_function(f"() => window.__kinetwork.file.path === {json.dumps(query['open'])}")
    elif "example" in query:
        page.wait_for_function(f"() => window.__kinetwork.file.example === "
                               f"{json.dumps(query['example'])}")
    if "open" in query or "example" in query:
        for comp in K(page, "K.doc.components.map(c => c.name)"):
            page.wait_for_selector(tid(f"node-{comp}"))
    return seconds


def wait_validated(page):
    """Wait for the debounced validation of the current document to answer."""
    page.wait_for_function("() => window.__kinetwork.validated")


#: where an element is once it has stopped moving: its rectangle the same over three frames
#: in a row (a diagram just opened is still being fitted into view, a pane resized)
SETTLED = """(sel) => new Promise((done) => {
    let last = null, same = 0, frames = 0;
    const look = () => {
        const el = document.querySelector(sel);
        const r = el && el.getBoundingClientRect();
        const now = r && [r.left, r.top, r.width, r.height].join();
        same = now && now === last ? same + 1 : 0;
        last = now;
        if (same >= 3 || ++frames > 300) done(r && {x: r.left, y: r.top, width: r.width, height: r.height});
        else requestAnimationFrame(look);
    };
    look();
})"""


def center(page, selector):
    """The middle of the element ``selector`` on screen, once it stands still (a click
    computed while the view still moves would land beside it)."""
    box = page.evaluate(SETTLED, selector)
    assert box, f"{selector} is not on screen"
    return box["x"] + box["width"] / 2, box["y"] + box["height"] / 2


def place(page, type_, name, x, y):
    """Drag ``type_`` from the palette onto the canvas, its block's top-left corner at
    (x, y) of the canvas (screen pixels), and name it ``name`` in the parameter panel."""
    before = K(page, "K.doc.components.length")
    page.locator(tid(f"palette-{type_}")).scroll_into_view_if_needed()
    page.drag_and_drop(tid(f"palette-{type_}"), tid("canvas"),
                       target_position={"x": x + 58, "y": y + 32})
    page.wait_for_function(f"() => window.__kinetwork.doc.components.length === {before + 1}")
    fresh = K(page, "K.doc.components[K.doc.components.length - 1].name")
    page.wait_for_function(f"() => window.__kinetwork.selection.join() === {json.dumps(fresh)}")
    if fresh != name:
        field = page.locator(tid("param-name"))
        field.fill(name)
        field.press("Enter")
    page.wait_for_selector(tid(f"node-{name}"))
    return fresh


def wire(page, a, b):
    """Drag with the mouse from port ``a`` ("comp.port") to port ``b``."""
    (ca, pa), (cb, pb) = a.split("."), b.split(".")
    x1, y1 = center(page, tid(f"handle-{ca}-{pa}"))
    x2, y2 = center(page, tid(f"handle-{cb}-{pb}"))
    page.mouse.move(x1, y1)
    page.mouse.down()
    page.mouse.move((x1 + x2) / 2, (y1 + y2) / 2 + 7, steps=6)
    page.mouse.move(x2, y2, steps=6)
    page.mouse.up()


def select(page, name):
    """Select one block by clicking its name."""
    page.locator(f'{tid(f"node-{name}")} .kn-block-name').click()
    page.wait_for_function(f"() => window.__kinetwork.selection.join() === {json.dumps(name)}")


def deselect(page):
    box = page.locator(tid("canvas")).bounding_box()
    page.mouse.click(box["x"] + box["width"] - 60, box["y"] + 20)
    page.wait_for_function("() => window.__kinetwork.selection.length === 0")


def set_field(page, testid, text):
    field = page.locator(tid(testid))
    field.fill(text)
    field.press("Enter")


def open_file(page, path):
    """Open ``path`` through the Open dialog's file list (discarding unsaved changes when
    the page asks); wait for its blocks."""
    _open_by_dialog(page, f"file-{path}",
                    f"window.__kinetwork.file.path === {json.dumps(path)}")


def open_in_page(page, **query):
    """Open a model in the page already loaded, the user's way: the Open dialog, an example
    (``example=name``) or a file of the studio's folder (``open=path``), discarding unsaved
    changes when the page asks; wait until its blocks are drawn. The same document, fit and
    routing as loading the page's address with that query, without loading the page again
    (~1 s of the browser's CPU each time)."""
    (key, value), = query.items()
    field = {"open": "path", "example": "example"}[key]
    asked = K(page, "K.store.getState().fitRequest")
    _open_by_dialog(page, f"{'file' if key == 'open' else 'example'}-{value}",
                    f"window.__kinetwork.file.{field} === {json.dumps(value)} && "
                    f"window.__kinetwork.store.getState().fitRequest > {asked}")


def _open_by_dialog(page, item, opened):
    """Open, then ``item`` (a test id) in the dialog's list; discard unsaved changes when
    the page asks; wait until ``opened`` (a JavaScript condition) holds and the model's
    blocks are drawn."""
    page.click(tid("open"))
    page.click(tid(item))
    page.wait_for_function(f"() => ({opened}) || "
                           f"!!document.querySelector('[data-testid=confirm-discard]')")
    if page.locator(tid("confirm-discard")).count():
        page.click(tid("choice-discard"))
    page.wait_for_selector(tid("open-dialog"), state="detached")
    page.wait_for_function(f"() => {opened}")
    for comp in K(page, "K.doc.components.map(c => c.name)"):
        page.wait_for_selector(tid(f"node-{comp}"))


def run(page, timeout=RUN_TIMEOUT):
    """Press Run, wait for the run to end; its final state."""
    n = K(page, "(K.runs || []).length ? K.runs[0].n : 0")
    page.click(tid("run"))
    page.wait_for_function(
        "() => { const s = window.__kinetwork.runState; return s && s.state !== 'running' "
        "&& s.state !== 'starting'; }", timeout=timeout)
    state = K(page, "K.runState.state")
    if state == "done":
        page.wait_for_function(f"() => window.__kinetwork.runs.length && "
                               f"window.__kinetwork.runs[0].n > {n}")
    return state


def leave(page, url):
    """Go to ``url``, answering "leave" if the page asks about unsaved changes."""
    def accept(dialog):
        if dialog.type == "beforeunload":
            dialog.accept()
    page.on("dialog", accept)
    try:
        page.goto(url)
    finally:
        page.remove_listener("dialog", accept)


#: the page's panes, each holding its controls
PANES = {"bar": ".kn-bar", "palette": tid("palette"), "diagram": ".kn-crumbs, " + tid("canvas"),
         "bars": ".kn-bars", "plots": tid("plots"), "viewer": tid("viewer"), "side": ".kn-right",
         "dialog": ".kn-modal", "menu": ".kn-menu", "toast": ".kn-toast"}

#: what is wrong with where things are, from the page's element rectangles: every pane must
#: lie in the window; every element a user reads (one with text of its own) or clicks (a
#: control, a role of one, or the pointer cursor) must lie within its pane, and its text and
#: box must not be cut by an ancestor that clips (overflow other than visible) unless that
#: ancestor scrolls along that axis with a scrollbar to say so (the user scrolls to it: the
#: ancestor is what must then be in view) or the text is elided on purpose (text-overflow:
#: ellipsis on the clipping box and the full text in a title on the element or above it);
#: an empty field's hint (placeholder) fits its field or is elided so, whole in a title.
#: Hidden elements (display, visibility, opacity) and the diagram's pan-and-zoom layer (the
#: user pans to its blocks) are not checked.
PLACES = """(panes) => {
    const SLACK = 1;
    const rect = (r) => ({x0: r.left, y0: r.top, x1: r.right, y1: r.bottom});
    const flat = (s) => s.replace(/\\s+/g, " ").trim();
    const hidden = (el) => { const s = getComputedStyle(el);
        return !el.getClientRects().length || s.visibility === "hidden" || s.opacity === "0"; };
    const clickable = (el) => el.matches("button, input, select, textarea, a[href], [role=tab], " +
            "[role=button], [role=menuitem]") || (getComputedStyle(el).cursor === "pointer" &&
            !(el.parentElement && getComputedStyle(el.parentElement).cursor === "pointer"));
    const ownText = (el) => [...el.childNodes].filter((n) => n.nodeType === 3 && n.textContent.trim());
    const titled = (el, upto, text) => { for (let e = el; e; e = e.parentElement) {
            if (e.title && flat(e.title).includes(text)) return true;
            if (e === upto) break; } return false; };
    const out = {viewport: {x0: 0, y0: 0, x1: innerWidth, y1: innerHeight}, panes: {},
                 wrong: [], controls: {}};
    const label = (el) => el.dataset.testid || flat(el.title || "").slice(0, 30) ||
            flat(el.textContent).slice(0, 30) || el.tagName.toLowerCase() + "." + el.className;
    const where = (b) => `[${Math.round(b.x0)},${Math.round(b.y0)} ${Math.round(b.x1)},${Math.round(b.y1)}]`;
    // what clips ``r`` between ``el`` (itself included when ``self``) and the pane
    const check = (name, pane, el, r, self, text) => {
        r = {...r};
        for (let a = self ? el : el.parentElement; a; a = a.parentElement) {
            const s = getComputedStyle(a);
            const c = rect(a.getBoundingClientRect());
            for (const k of ["x", "y"]) {
                const overflow = k === "x" ? s.overflowX : s.overflowY;
                if (overflow === "visible") continue;
                const cut = r[k + "0"] < c[k + "0"] - SLACK || r[k + "1"] > c[k + "1"] + SLACK;
                const long = k === "x" ? a.scrollWidth > a.clientWidth + 1 : a.scrollHeight > a.clientHeight + 1;
                // (sideways only a scrollbar that takes room says there is more: overlay
                // scrollbars, the default of many systems and of headless Chromium, do not)
                const bar = k === "y" || a.offsetHeight - a.clientHeight > 2 * parseFloat(s.borderBottomWidth) + 1;
                if (/auto|scroll/.test(overflow) && long && bar) {
                    // reached by scrolling this box: from here up, it is the box that counts
                    r[k + "0"] = Math.max(r[k + "0"], c[k + "0"]); r[k + "1"] = Math.min(r[k + "1"], c[k + "1"]);
                    if (r[k + "1"] < r[k + "0"]) { r[k + "0"] = c[k + "0"]; r[k + "1"] = c[k + "1"]; }
                    continue;
                }
                if (!cut) continue;
                if (k === "x" && text && s.textOverflow === "ellipsis" && titled(el, pane, text)) {
                    r.x0 = Math.max(r.x0, c.x0); r.x1 = Math.min(r.x1, c.x1);
                    continue;
                }
                out.wrong.push(`${name}: ${JSON.stringify(label(el))} at ${where(r)} cut along ${k} ` +
                    `by ${a.tagName.toLowerCase()}.${String(a.className).split(" ")[0]} ${where(c)}` +
                    (text && s.textOverflow === "ellipsis" ? " (elided, but no title holds its text)" : ""));
                return;
            }
            if (a === pane) break;
        }
        const p = out.panes[name];
        if (!(r.x0 >= p.x0 - SLACK && r.x1 <= p.x1 + SLACK && r.y0 >= p.y0 - SLACK && r.y1 <= p.y1 + SLACK))
            out.wrong.push(`${name}: ${JSON.stringify(label(el))} at ${where(r)} outside its pane ${where(p)}`);
    };
    const every = Object.values(panes).join(", ");
    const pen = document.createElement("canvas").getContext("2d");
    for (const [name, sel] of Object.entries(panes)) {
        for (const [i, pane] of [...document.querySelectorAll(sel)].entries()) {
            if (hidden(pane)) continue;
            const key = i ? `${name}${i}` : name;
            out.panes[key] = rect(pane.getBoundingClientRect());
            for (const el of pane.querySelectorAll("*")) {
                // a pane's own (a dialog opened from a pane is a pane of its own)
                if (el.closest(every) !== pane) continue;
                if (el.closest("svg, .react-flow__viewport") || el.parentElement.closest("select") ||
                        hidden(el)) continue;
                const texts = ownText(el);
                const click = clickable(el);
                if (!texts.length && !click) continue;
                if (click) (out.controls[key] = out.controls[key] || []).push(label(el));
                if (click) check(key, pane, el, rect(el.getBoundingClientRect()), false, null);
                // an empty field's hint: as wide as the field, or elided and whole in a title
                if (el.matches("input") && el.placeholder && !el.value) {
                    const s = getComputedStyle(el);
                    pen.font = `${s.fontStyle} ${s.fontWeight} ${s.fontSize} ${s.fontFamily}`;
                    const room = el.clientWidth - parseFloat(s.paddingLeft) - parseFloat(s.paddingRight);
                    if (pen.measureText(el.placeholder).width > room + SLACK &&
                            !(s.textOverflow === "ellipsis" && titled(el, pane, flat(el.placeholder))))
                        out.wrong.push(`${key}: ${JSON.stringify(label(el))}'s hint ` +
                            `${JSON.stringify(el.placeholder)} cut by its field (${Math.round(room)} px)`);
                }
                for (const t of texts) {
                    const range = document.createRange();
                    range.selectNodeContents(t);
                    const b = range.getBoundingClientRect();
                    if (b.width && b.height) check(key, pane, el, rect(b), true, flat(t.textContent));
                }
            }
        }
    }
    for (const [name, b] of Object.entries(out.panes))
        if (!(b.x0 >= -SLACK && b.y0 >= -SLACK && b.x1 <= innerWidth + SLACK && b.y1 <= innerHeight + SLACK))
            out.wrong.push(`pane ${name} ${where(b)} outside the window`);
    return out;
}"""


def misplaced(page):
    """Every pane outside the window, and everything a user reads or clicks that is outside
    its pane or cut (PLACES): the list of what is wrong, and the panes' rectangles and
    controls."""
    places = page.evaluate(PLACES, PANES)
    return places["wrong"], places


def chromium_cpu():
    """CPU seconds so far of this process's Chromium children, by kind: "renderer", "gpu"
    (the GPU process: SwiftShader draws there, and the display compositor), "other". Read
    from /proc (Linux); Chromium rewrites its command lines, so a kind is told by its flags."""
    children = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                parent = int(procstat.stat(entry)[1])
            except OSError:               # gone meanwhile
                continue
            children.setdefault(parent, []).append(int(entry))
    spent, todo = {}, [os.getpid()]
    while todo:
        for pid in children.get(todo.pop(), []):
            todo.append(pid)
            try:
                line = pathlib.Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace")
                fields = procstat.stat(pid)
            except OSError:
                continue
            if "chromium" not in line and "--type=" not in line and "--gpu-preferences" not in line:
                continue                  # the Playwright driver (node)
            kind = ("gpu" if "--gpu-preferences" in line else
                    "renderer" if "--renderer-client-id" in line else "other")
            spent[kind] = spent.get(kind, 0.0) + procstat.cpu_seconds(fields=fields)
    return spent
