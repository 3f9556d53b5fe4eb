"""The studio's fold of a repeated pattern into subsystems (frontend/src/studio/fold.js)
keeps the model's meaning: the folded file, read by kinetwork, moves exactly as the flat
one. The fold is the page's own code, run by Node on the model's JSON; the motion of both
files is kinetwork's, compared state by state (``jK.q`` against ``linkK.j.q``)."""

import json
import shutil
import subprocess

import numpy as np
from browser import browser_missing

import kinetwork as kn
from tests.scenes.chains import chain
from tests.studio.conftest import FRONTEND

FOLD = """
import { readFileSync, writeFileSync } from "node:fs";
const { findRepeat, foldRepeat } = await import(process.argv[2]);
const doc = JSON.parse(readFileSync(process.argv[3], "utf8"));
const found = findRepeat(doc);
if (!found) { writeFileSync(process.argv[4], "null"); process.exit(0); }
const { body, definition } = foldRepeat(doc, found, "Link");
writeFileSync(process.argv[4], JSON.stringify({ ...body, version: 2, definitions: { Link: definition } }));
"""


def fold(tmp_path, doc):
    """The document folded by the page's code (None when it finds nothing to fold)."""
    if shutil.which("node") is None:
        browser_missing("Node is needed to run the studio's fold (apt-get install nodejs)")
    script = tmp_path / "fold.mjs"
    script.write_text(FOLD)
    src, out = tmp_path / "flat.json", tmp_path / "folded.json"
    src.write_text(json.dumps(doc))
    subprocess.run(["node", str(script), str(FRONTEND / "src" / "studio" / "fold.js"), str(src),
                    str(out)], check=True, capture_output=True, timeout=120)
    return json.loads(out.read_text())


def chain_doc(tmp_path, n):
    chain(n).save(tmp_path / "chain.json")
    return json.loads((tmp_path / "chain.json").read_text())


def test_folded_chain_moves_as_the_flat_one(tmp_path):
    """Six links with different initial angles and rates and a mass given by the model's
    parameter: six instances of one definition, each giving its own angles, the parameter
    passed through; the joint angles agree to the integration's tolerance."""
    doc = chain_doc(tmp_path, 6)
    doc["parameters"] = {"m": 1.5}
    for k, comp in enumerate(c for c in doc["components"] if c["type"].endswith("Revolute")):
        comp["params"]["q0"] = 0.1 * k + 0.2
        comp["params"]["qd0"] = -0.05 * k
    for comp in doc["components"]:
        if comp["type"].endswith("RigidBody"):
            comp["params"]["mass"] = "m"
    folded = fold(tmp_path, doc)
    assert [c["type"] for c in folded["components"]] == ["multibody.Ground"] + ["Link"] * 6
    link = folded["definitions"]["Link"]
    assert [c["name"] for c in link["components"]] == ["j", "b", "l"]
    assert folded["components"][3]["params"] == {"m": "m", "j_q0": 0.4, "j_qd0": -0.1}
    a = kn.simulate(kn.loads(json.dumps(doc)), t_end=1.0, n_points=51, rtol=1e-10, atol=1e-12)
    b = kn.simulate(kn.loads(json.dumps(folded)), t_end=1.0, n_points=51, rtol=1e-10, atol=1e-12)
    for k in range(6):
        assert np.allclose(a[f"j{k}.q"], b[f"link{k}.j.q"], rtol=0, atol=1e-7), k
    assert np.ptp(a["j5.q"]) > 0.1      # the chain moves: the comparison is not of constants


def test_no_fold_where_the_units_differ(tmp_path):
    """Four links, one of them wired otherwise (its body hung on the translation's end) or
    with a value that cannot be a definition's parameter (an expression in one link only):
    no three alike units in a row, nothing folded."""
    doc = chain_doc(tmp_path, 4)
    wired = json.loads(json.dumps(doc))
    wired["connections"] = [["l1.frame_b", "b1.frame_a"] if c == ["j1.frame_b", "b1.frame_a"]
                            else c for c in wired["connections"]]
    assert fold(tmp_path, wired) is None
    expr = json.loads(json.dumps(doc))
    expr["parameters"] = {"L": 1.0}
    b1 = next(c for c in expr["components"] if c["name"] == "b1")
    b1["params"]["mass"] = "2*L"
    assert fold(tmp_path, expr) is None
