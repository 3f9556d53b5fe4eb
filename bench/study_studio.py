"""The studio's speed in headless Chromium: its load (navigation to the palette ready), Run
to plotted results for the seed and for EngineV6 (median of 3, compiled), and the 3-D view's
frame rate and draw calls a frame for a 32-link chain, beside the frame rate of an empty page
in the same
browser (the ceiling: headless Chromium's frames come at 60 a second at most); for both, the
gaps between frames (one frame, two: a frame dropped, more) and the CPU time a frame of
Chromium's renderer and GPU processes. The measurement is the browser test marked ``bench`` in
tests/studio/test_e2e.py (the suite leaves it out: timings never go in a test); this runs it
and writes ``results/studio.md`` from the figures it records.

Run: ``python bench/study_studio.py [--quick]`` (needs the test extras and Debian's Chromium).
"""

import os
import subprocess
import sys
import xml.etree.ElementTree as ET

from common import HERE, RESULTS, machine

TEST = "tests/studio/test_e2e.py::test_measure_load_run_and_3d_frame_rate"


#: what a frame of the 32-link chain costs, and what drops frames: a study of this round
#: (not measured again by this script; its figures above are)
COSTS = """## What a frame of the playing chain costs (study of 2026-11-29, load 1.6-8.7)

From Chrome traces of the chain playing (2-2.5 s each), CPU time of Chromium's processes
read from /proc while it played, and the view's shapes hidden kind by kind:

- **The picture is drawn while the page waits.** With software compositing, each frame the
  page hands the compositor a copy of the picture, read back from the GPU process
  (`ReadPixels`, a `Finish`): the page's main thread waits 4-6 ms a frame for SwiftShader to
  draw it. The page's own work in a plain frame is 0.5-0.9 ms (`tick`: poses, batches,
  `render` calls). So a plain frame takes ~6-7 ms of the 16.7 ms, and the machine's other
  load decides whether it fits.
- **The GPU process's 5.5-6.5 ms a frame are the shapes' triangles and pixels, not their
  draw calls.** Hiding kinds in turn: nothing drawn 0.9 ms, the ground's grid alone 1.4 ms,
  everything 5.5-6.5 ms; ratio 0.5 instead of 1 saves ~1 ms. The number of calls made no
  difference, measured A/B in alternate browser sessions (CPU ms of the GPU process a frame,
  4 x 4 s each): 6 calls (arrow shafts and heads apart) 5.46 against 5 calls 5.45; the lit
  kinds in one call (a shader fetching each shape's matrix from a texture; not kept) 5.67
  against 5.81; each kind's instances merged into one mesh moved in JavaScript (not kept)
  5.5 against 5.7, for 1 ms more of the page's time. (A first reading, kinds hidden one after
  another while the load changed, had put ~0.7 ms on every call: the A/B runs disprove it.)
- **The frames that change the page are the long ones.** Ten times a second the time label
  and the plots' cursors move (together, one frame in six): that frame adds style and
  layout 0.7 ms, paint 1.8 ms, layerization 2.0-2.5 ms and commit 0.3-1.8 ms, and came
  19.5-21 ms after the one before. With the cursors and the bar on layers of their own
  (`will-change`), their layerization is 1.0 ms and they come 16.8-18 ms apart (three traces
  each, alternated). Hiding the legends changed nothing measurable (one trace).
- **Not garbage collection, not the pixel budget.** The page's heap grew 136 KB a second
  (~2 KB a frame, the trace's heap counters) and was not collected in the 2 s traced; the
  pixel ratio stayed 1 while frames kept up (it settles at 0.75 when they come slower than
  45 a second), and 0.5 instead of 1 saves only ~1 ms of the GPU process.
- **Dropped frames come in bursts with the machine's load**, not with the view: an idle
  moment plays 240 of 240 frames; under load 3-5 two to nine gaps of two frames in 4 s while
  an empty page in the same browser keeps 60; at load 8.7 the empty page itself fell to 52.8
  frames/s and the chain played 55.0.

What is left: the main thread waits for the picture every frame. Drawing in a worker
(`OffscreenCanvas` transferred to it) would take that wait off the page's frames; the
picture's own rate would then be measured in the worker.
"""


def main():
    RESULTS.mkdir(exist_ok=True)
    report = RESULTS / "studio_junit.xml"
    before = os.getloadavg()[0]
    code = subprocess.call([sys.executable, "-m", "pytest", "-q", "-s", "-m", "bench",
                            "-p", "no:cacheprovider", "-o", "junit_family=xunit1", TEST,
                            f"--junitxml={report}"],
                           cwd=HERE.parent)
    if code:
        sys.exit(f"the studio's measurement failed (pytest exit code {code})")
    figures = {p.get("name"): float(p.get("value"))
               for p in ET.parse(report).getroot().iter("property")}
    report.unlink()
    after = os.getloadavg()[0]
    f = figures
    frames = "".join(
        f"| {what} | {f[k + '_fps']:.1f} | {f[k + '_gaps_1']:.0f} / {f[k + '_gaps_2']:.0f} / "
        f"{f[k + '_gaps_more']:.0f} | {f[k + '_renderer_ms']:.2f} | {f[k + '_gpu_ms']:.2f} |\n"
        for what, k in (("3-D view of a 32-link chain, playing", "chain32"),
                        ("an empty page in the same browser (the ceiling)", "empty_page")))
    (RESULTS / "studio.md").write_text(
        "# The studio in headless Chromium\n\n"
        f"{machine()}; load average (1 min) {before:.1f} before the run, {after:.1f} after: "
        "every figure here scales with what else the machine does.\n\n"
        "| measure | value |\n| --- | ---: |\n"
        f"| load, navigation to the palette ready (median of 3) | {f['load_s']:.2f} s |\n"
        f"| seed: Run to plotted results (median of 3, compiled) | "
        f"{f['run_to_plot_s']:.2f} s |\n"
        f"| EngineV6 (6 loops, 337 events; the plots' 0.4 MB ahead of the 3-D view's 5.7 MB): "
        f"Run to plotted results (median of 3, cached) | {f['engine_run_to_plot_s']:.2f} s |\n"
        f"| 3-D view of a 32-link chain, draw calls a frame | {f['chain32_draw_calls']:.0f} |\n"
        f"| 3-D view of a 32-link chain, triangles a frame | {f['chain32_triangles']:.0f} |\n"
        f"| 3-D view of a 32-link chain, pixel ratio after playing | "
        f"{f['chain32_pixel_ratio']:.2f} |\n\n"
        "Frames over 4 s: frames a second; the gaps between frames of one frame (under 25 ms), "
        "two (a frame dropped) and more; the CPU time a frame of Chromium's renderer process "
        "(the page's scripts, style, paint, handing the picture on; not its waits) and GPU process (SwiftShader "
        "drawing the picture, the display compositor).\n\n"
        "| page | frames/s | gaps: 1 / 2 / more | renderer ms/frame | GPU process ms/frame |\n"
        "| --- | ---: | ---: | ---: | ---: |\n" + frames + "\n" + COSTS)
    print((RESULTS / "studio.md").read_text())


if __name__ == "__main__":
    main()
