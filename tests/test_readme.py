"""The README's component table and example stay in step with the code."""

import pathlib
import re

import numpy as np

import kinetwork as kn

from kinetwork.components.base import REGISTRY

README = (pathlib.Path(__file__).resolve().parents[1] / "README.md").read_text()


def test_every_component_is_listed():
    """Each row's first cell names a type and its siblings: `lib.A` / `B` / `C`."""
    table = README.split("## Components", 1)[1].split("\n## ", 1)[0]
    listed = set()
    for row in re.findall(r"^\| ([^|]+)\|", table, re.M):
        names = re.findall(r"`([^`]+)`", row)
        if not names:
            continue
        lib = names[0].rsplit(".", 1)[0] if "." in names[0] else ""
        listed.add(names[0])
        listed.update(f"{lib}.{n}" for n in names[1:])
    missing = sorted(set(REGISTRY) - listed)
    assert not missing, f"components missing from README: {missing}"


def test_python_example_runs(tmp_path, monkeypatch):
    code = README.split("## In Python", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(compile(code, "README.md", "exec"), scope)          # our own README, not user input
    res = scope["res"]
    q, qd = res["shoulder.q"], res["shoulder.qd"]
    np.testing.assert_allclose(res["probe1.torque"], -(2.0 * q + 1.0 * qd), atol=1e-12)
    assert (tmp_path / "probes.png").stat().st_size > 10_000


def test_subsystem_example_runs():
    code = README.split("## Subsystems", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    scope = {"kn": kn}
    exec(compile(code, "README.md", "exec"), scope)          # our own README, not user input
    res = scope["res"]
    assert res.state_names[:2] == ["upper.joint.q", "lower.joint.q"]
    assert res["lower.p.angle"].shape == res.t.shape
