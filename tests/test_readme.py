"""The README's example and the docs' component table and subsystem example stay in step
with the code. The README is a front door: the reference it held lives on the docs pages."""

import pathlib
import re

import numpy as np

import kinetwork as kn

from kinetwork.components.base import REGISTRY

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
OVERVIEW = (ROOT / "docs" / "reference" / "overview.md").read_text()
SUBSYSTEMS = (ROOT / "docs" / "how-to" / "subsystems.md").read_text()


def test_every_component_is_listed():
    """Each row's first cell names a type and its siblings: `lib.A` / `B` / `C`."""
    listed = set()
    for row in re.findall(r"^\| ([^|]+)\|", OVERVIEW, re.M):
        names = re.findall(r"`([^`]+)`", row)
        if not names:
            continue
        lib = names[0].rsplit(".", 1)[0] if "." in names[0] else ""
        listed.add(names[0])
        listed.update(f"{lib}.{n}" for n in names[1:])
    missing = sorted(set(REGISTRY) - listed)
    assert not missing, f"components missing from docs/reference/overview.md: {missing}"


def test_python_example_runs(tmp_path, monkeypatch):
    code = README.split("## In Python", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(compile(code, "README.md", "exec"), scope)          # our own README, not user input
    res = scope["res"]
    q, qd = res["shoulder.q"], res["shoulder.qd"]
    np.testing.assert_allclose(res["probe1.torque"], -(2.0 * q + 1.0 * qd), atol=1e-12)
    assert (tmp_path / "probes.png").stat().st_size > 10_000
    assert kn.read_csv(tmp_path / "out.csv").units["probe1.torque"] == "N*m"


def test_the_readme_is_a_front_door():
    """What it is, the picture, the two commands, an example of about 20 lines, links."""
    example = README.split("```python", 1)[1].split("```", 1)[0].strip().splitlines()
    assert len(example) <= 25 and len(README.splitlines()) < 120
    assert "make demo" in README and "make test" in README
    assert "docs/double_pendulum_probes.png" in README
    for link in re.findall(r"\]\((docs/[^)#]+)\)", README):
        assert (ROOT / link).exists(), link


def test_subsystem_example_runs():
    code = SUBSYSTEMS.split("```python", 1)[1].split("```", 1)[0]
    scope = {"kn": kn}
    exec(compile(code, "subsystems.md", "exec"), scope)      # our own docs, not user input
    res = scope["res"]
    assert res.state_names[:2] == ["upper.joint.q", "lower.joint.q"]
    assert res["lower.p.angle"].shape == res.t.shape
