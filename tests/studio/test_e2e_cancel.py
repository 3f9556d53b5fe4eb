"""Cancel that is instant and visible (issue 29 item 2), in headless Chromium: the button says
"Cancelling" as it is clicked, the run stops where it was (in its integration: what it reached
is kept and plotted, marked partial; while compiling: nothing lost, nothing computed) and the
next run works. No wall-time bound: how far the run got after the click is checked instead
(the numbers of the report are printed)."""

import time

from tests.studio.helpers import RUN_TIMEOUT, K, deselect, open_studio, run, set_field, tid

SEED = "models/double_pendulum.json"


def long_run(page, t_end="200000", n_points="100001"):
    deselect(page)
    set_field(page, "sim-t_end", t_end)
    set_field(page, "sim-n_points", n_points)
    set_field(page, "sim-rtol", "1e-12")
    set_field(page, "sim-atol", "1e-14")


# what the page showed, change by change, from the click on Cancel on: the button's state and
# the status line, read by a MutationObserver in the page (read after the click from Python, the
# server's answer may already have come: on a loaded machine it once had, "cancelled")
WATCH = """() => {
  const look = () => ({
    button: document.querySelector('[data-testid="cancel"]')?.getAttribute('data-state'),
    label: document.querySelector('[data-testid="cancel"]')?.innerText,
    disabled: document.querySelector('[data-testid="cancel"]')?.disabled,
    status: document.querySelector('[data-testid="run-status"]')?.innerText,
  });
  const seen = [];
  window.__cancelSeen = seen;
  document.addEventListener('click', e => {
    if (e.target.closest('[data-testid="cancel"]')) seen.push({ clicked: true });
  }, true);
  new MutationObserver(() => {
    const now = look(), last = seen[seen.length - 1];
    if (!last || JSON.stringify(last) !== JSON.stringify(now)) seen.push(now);
  }).observe(document.body, { subtree: true, childList: true, characterData: true,
                              attributes: true });
}"""


def click_cancel_and_see_it_at_once(page):
    """Click Cancel with the mouse; the first thing the page shows after it is "cancelling", on
    the button (disabled) and on the status line, before the server's answer."""
    page.evaluate(WATCH)
    page.click(tid("cancel"))
    page.wait_for_function("() => window.__cancelSeen.some(s => s.clicked)")
    page.wait_for_function("() => { const s = window.__cancelSeen; "
                           "return s.length > s.findIndex(x => x.clicked) + 1; }")
    seen = page.evaluate("() => window.__cancelSeen")
    first = seen[[s.get("clicked") for s in seen].index(True) + 1]
    assert first["button"] == "cancelling", seen
    assert "Cancelling" in first["label"] and first["disabled"], seen
    assert first["status"] == "cancelling…", seen


def test_cancel_shows_at_once_stops_the_run_and_plots_what_it_reached(page, studio,
                                                                      record_property):
    open_studio(page, studio, open=SEED)
    long_run(page)
    page.click(tid("run"))
    page.wait_for_function("() => { const s = window.__kinetwork.runState; "
                           "return s && s.state === 'running' && s.progress > 0; }",
                           timeout=RUN_TIMEOUT)
    reached = K(page, "K.runState.progress")
    clicked = time.perf_counter()
    click_cancel_and_see_it_at_once(page)
    page.wait_for_function("() => window.__kinetwork.runState.state === 'cancelled'",
                           timeout=RUN_TIMEOUT)
    stopped = time.perf_counter() - clicked
    page.locator(tid("toast")).filter(has_text="partial").wait_for()
    results = K(page, "K.runs[0].results")
    t_end = 200000.0
    partial = results["partial"]
    assert partial["reason"] == "cancelled"
    # it stopped where it was: a small step past the progress seen at the click, not the end
    assert partial["t_reached"] < t_end * min(1.0, reached + 0.25), (reached, partial)
    assert 1 < len(results["t"]) < 100001
    # plotted, and said to be partial
    assert K(page, "K.plotted['probe1.angle'][0].length") == len(results["t"])
    header = page.locator(tid("plot-runs")).inner_text()
    assert "partial" in header and "run 1" in header
    record_property("cancel_to_stopped_s", stopped)
    print(f"\ncancel in the integration: stopped {stopped:.2f} s after the click, at "
          f"t = {partial['t_reached']:.0f} s of {t_end:.0f} s ({len(results['t'])} points)")
    # the next run works, and counts on
    set_field(page, "sim-t_end", "1")
    set_field(page, "sim-n_points", "101")
    assert run(page) == "done"
    assert K(page, "K.runs[0].n") == 2
    assert not page.errors, page.errors


def test_cancel_while_compiling_ends_it_with_nothing_lost(page, studio, record_property,
                                                         monkeypatch, tmp_path):
    # a build from nothing (the server runs in this process): with the run's shared caches
    # holding EngineV6 already, what is checked here, a cancel while compiling, may not be
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    monkeypatch.setenv("KINETWORK_CACHE", str(cache))
    monkeypatch.setenv("KINETWORK_BUILD_CACHE", "0")
    open_studio(page, studio, example="engine_v6/EngineV6")
    page.click(tid("run"))
    page.wait_for_function("() => { const s = window.__kinetwork.runState; "
                           "return s && s.state === 'running' && s.phase === 'compiling'; }",
                           timeout=RUN_TIMEOUT)
    clicked = time.perf_counter()
    click_cancel_and_see_it_at_once(page)
    page.wait_for_function("() => window.__kinetwork.runState.state === 'cancelled'",
                           timeout=RUN_TIMEOUT)
    stopped = time.perf_counter() - clicked
    assert K(page, "K.runs.length") == 0          # nothing was computed: nothing plotted
    page.locator(tid("toast")).filter(has_text="before it computed anything").wait_for()
    assert page.locator(tid("run")).is_enabled()
    record_property("cancel_compiling_to_stopped_s", stopped)
    print(f"\ncancel while compiling EngineV6: stopped {stopped:.2f} s after the click")
    assert not page.errors, page.errors
