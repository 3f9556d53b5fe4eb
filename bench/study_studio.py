"""The studio's speed in headless Chromium: its load (navigation to the palette ready), Run
to plotted results for the seed (median of 3, compiled), and the 3-D view's frame rate and
draw calls a frame for a 32-link chain, beside the frame rate of an empty page in the same
browser (the ceiling: headless Chromium's frames come at 60 a second at most). The measurement is the browser test marked ``bench`` in
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
    (RESULTS / "studio.md").write_text(
        "# The studio in headless Chromium\n\n"
        f"{machine()}; load average (1 min) {before:.1f} before the run, {after:.1f} after: "
        "every figure here scales with what else the machine does.\n\n"
        "| measure | value |\n| --- | ---: |\n"
        f"| load, navigation to the palette ready (median of 3) | {figures['load_s']:.2f} s |\n"
        f"| seed: Run to plotted results (median of 3, compiled) | "
        f"{figures['run_to_plot_s']:.2f} s |\n"
        f"| 3-D view of a 32-link chain, playing | {figures['chain32_fps']:.1f} frames/s |\n"
        f"| an empty page in the same browser (the ceiling) | "
        f"{figures['empty_page_fps']:.1f} frames/s |\n"
        f"| 3-D view of a 32-link chain, draw calls a frame | "
        f"{figures['chain32_draw_calls']:.0f} |\n"
        f"| 3-D view of a 32-link chain, triangles a frame | "
        f"{figures['chain32_triangles']:.0f} |\n"
        f"| 3-D view of a 32-link chain, pixel ratio after playing | "
        f"{figures['chain32_pixel_ratio']:.2f} |\n")
    print((RESULTS / "studio.md").read_text())


if __name__ == "__main__":
    main()
