"""Subsystems in files (format version 2): definitions inline, in another file of the model's
folder, next to the model, or in a library folder; what is saved; and the refusals, each
naming its path in the file."""

import json
import os

import jsonschema
import numpy as np
import pytest
from close import assert_same_numbers

import kinetwork as kn
from kinetwork.cli import main

from graph.test_subsystem import link_model, seed_of_links


def save(model, path):
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)


def write(path, data):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2))
    return path


def arm_file(definitions=None, link_type="link"):
    """The seed of links as a file's dict, placing the definition ``link_type``."""
    data = json.loads(kn.dumps(seed_of_links()))
    for entry in data["components"]:
        if entry["type"] == "link":
            entry["type"] = link_type
    if definitions is None:
        data.pop("definitions")
    else:
        data["definitions"] = definitions
    return data


def test_a_model_of_subsystems_is_saved_as_version_2_and_reads_back(tmp_path):
    arm = seed_of_links()
    arm.save(tmp_path / "arm.json")
    data = json.loads((tmp_path / "arm.json").read_text())
    assert data["version"] == 2
    assert list(data["definitions"]) == ["link"]
    assert data["definitions"]["link"]["ports"]["frame_b"] == "rod.frame_b"
    back = kn.load(tmp_path / "arm.json")
    assert kn.dumps(back) == kn.dumps(arm)
    a = kn.simulate(arm, t_end=1, n_points=11)
    b = kn.simulate(back, t_end=1, n_points=11)
    assert_same_numbers(a.states, b.states)
    validator = jsonschema.Draft202012Validator(kn.schema())
    assert list(validator.iter_errors(data)) == []


def test_a_flat_model_is_still_written_as_version_1(tmp_path, seed_model):
    text = kn.dumps(seed_model)
    assert json.loads(text)["version"] == 1 and "definitions" not in text
    # a version-2 file that needs nothing of version 2 is written back as version 1
    data = json.loads(text)
    data["version"] = 2
    assert kn.dumps(kn.loads(json.dumps(data))) == text


def test_definitions_in_files_of_the_folder_are_referenced_not_copied(tmp_path):
    save(link_model(), tmp_path / "parts" / "link.json")
    path = write(tmp_path / "arm.json", arm_file({"link": {"file": "parts/link.json"}}))
    arm = kn.load(path)
    res = kn.simulate(arm, t_end=1, n_points=11)
    assert res.signal_names[0] == "upper.p.angle"
    arm.save(tmp_path / "again.json")                 # same folder: the reference stays
    again = json.loads((tmp_path / "again.json").read_text())
    assert again["definitions"] == {"link": {"file": "parts/link.json"}}
    # saved where the reference would leave the folder: written inline, self-contained
    (tmp_path / "sub").mkdir()
    arm.save(tmp_path / "sub" / "copy.json")
    copy = json.loads((tmp_path / "sub" / "copy.json").read_text())
    assert copy["definitions"]["link"]["ports"]["axis"] == "joint.axis"
    # a definition edited after loading is saved inline: the file it came from is untouched
    before = (tmp_path / "parts" / "link.json").read_bytes()
    arm.components["upper"].definition.set_parameter("L", 2.0)
    arm.save(tmp_path / "edited.json")
    assert "file" not in json.loads((tmp_path / "edited.json").read_text())["definitions"]["link"]
    assert (tmp_path / "parts" / "link.json").read_bytes() == before


def test_one_definition_file_is_read_once_for_all_its_instances(tmp_path):
    save(link_model(), tmp_path / "link.json")
    arm = kn.load(write(tmp_path / "arm.json", arm_file()))    # found next to the model
    upper, lower = arm.components["upper"], arm.components["lower"]
    assert upper.definition is lower.definition
    arm.save(tmp_path / "arm.json")                             # and found there again
    assert "definitions" not in json.loads((tmp_path / "arm.json").read_text())


def test_a_library_folder_is_searched_after_the_file_and_its_folder(tmp_path, monkeypatch,
                                                                   capsys):
    library = tmp_path / "library"
    save(link_model(), library / "link.json")
    path = write(tmp_path / "models" / "arm.json", arm_file())
    with pytest.raises(kn.ModelError, match=r'components\[1\] "upper": unknown type \'link\': '
                                            r"no kinetwork component, nor a definition in "
                                            r"this file; looked for link.json in"):
        kn.load(path)
    arm = kn.load(path, library=[library])
    assert arm.components["upper"].definition.origin[1] == "library"
    arm.save(path)                       # the library finds it again: not copied in
    assert "definitions" not in json.loads(path.read_text())
    monkeypatch.setenv("KINETWORK_LIBRARY", str(library))
    assert kn.load(path).compile().n_states == 4
    monkeypatch.delenv("KINETWORK_LIBRARY")
    assert main(["validate", str(path), "--library", str(library)]) == 0
    out = capsys.readouterr().out
    assert "subsystems: 1 definition, 2 instances; flat: 10 components" in out
    assert "link (library " in out and "): upper, lower" in out
    assert main(["run", str(path), "--library", str(library), "--t-end", "0.1", "-q",
                 "--out", str(tmp_path / "out.csv")]) == 0
    header = (tmp_path / "out.csv").read_text().splitlines()[0]
    assert header == "t,upper.p.angle,upper.p.speed,lower.p.angle,lower.p.speed"


def test_validate_summarises_a_definition_file(tmp_path, capsys):
    path = tmp_path / "link.json"
    link_model().save(path)
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out
    assert "subsystem definition 'link'" in out
    assert "frame_a -> joint.frame_a (frame)" in out


# -- refusals -----------------------------------------------------------------------------
def inline_link():
    return json.loads(kn.dumps(seed_of_links()))["definitions"]["link"]


def refused(path, *patterns, **kwargs):
    with pytest.raises(kn.ModelError) as err:
        kn.load(path, **kwargs)
    text = str(err.value)
    for pattern in patterns:
        assert pattern in text, text
    return text


def test_a_missing_definition_is_refused_naming_the_component(tmp_path):
    path = write(tmp_path / "arm.json", arm_file({}, link_type="lnk"))
    refused(path, 'components[1] "upper": unknown type \'lnk\'',
            'components[2] "lower": unknown type \'lnk\'')


def test_a_cycle_of_definitions_is_refused_naming_it(tmp_path):
    a = {"ports": {"f": "b1.f"}, "components": [{"name": "b1", "type": "B"}]}
    b = {"ports": {"f": "a1.f"}, "components": [{"name": "a1", "type": "A"}]}
    data = arm_file({"link": inline_link(), "A": a, "B": b})
    path = write(tmp_path / "arm.json", data)
    refused(path, "definitions.A", "definitions place each other in a cycle: A places B "
                                   "places A")
    # across files: a.json places B of b.json, which places A of a.json
    write(tmp_path / "lib" / "A.json", {"format": "kinetwork.model", "version": 2, "name": "A",
                                        "ports": {"f": "b1.f"},
                                        "components": [{"name": "b1", "type": "B"}],
                                        "definitions": {"B": {"file": "B.json"}}})
    write(tmp_path / "lib" / "B.json", {"format": "kinetwork.model", "version": 2, "name": "B",
                                        "ports": {"f": "a1.f"},
                                        "components": [{"name": "a1", "type": "A"}],
                                        "definitions": {"A": {"file": "A.json"}}})
    data = arm_file({"link": inline_link(), "A": {"file": "lib/A.json"}})
    refused(write(tmp_path / "arm2.json", data), "definitions.A",
            "files reference each other in a cycle: lib/A.json references lib/B.json "
            "references lib/A.json")


@pytest.mark.parametrize("ref, message", [
    ("../outside.json", "leaves the model's folder"),
    ("parts/../../outside.json", "leaves the model's folder"),
    ("/etc/passwd", "must be a path relative to the model's folder"),
    ("https://example.com/link.json", "no URL"),
    ("file:///etc/passwd", "no URL"),
])
def test_a_reference_leaving_the_folder_is_refused(tmp_path, ref, message):
    save(link_model(), tmp_path / "outside.json")
    path = write(tmp_path / "models" / "arm.json", arm_file({"link": {"file": ref}}))
    refused(path, "definitions.link file", message)


def test_a_symbolic_link_out_of_the_folder_is_refused(tmp_path):
    save(link_model(), tmp_path / "outside" / "link.json")
    (tmp_path / "models").mkdir()
    os.symlink(tmp_path / "outside" / "link.json", tmp_path / "models" / "sneaky.json")
    path = write(tmp_path / "models" / "arm.json", arm_file({"link": {"file": "sneaky.json"}}))
    refused(path, "leaves the model's folder")


def test_a_wrong_exposed_port_is_refused_naming_its_path(tmp_path):
    link = inline_link()
    link["ports"]["frame_b"] = "rod.frame_x"
    path = write(tmp_path / "arm.json", arm_file({"link": link}))
    refused(path, 'definitions.link.ports.frame_b "rod.frame_x": FixedTranslation \'rod\' has '
                  "no port 'frame_x'")
    # and in a definition's own file
    save(link_model(), tmp_path / "parts" / "link.json")
    text = (tmp_path / "parts" / "link.json").read_text().replace('"joint.axis"', '"joint.ax"')
    (tmp_path / "parts" / "link.json").write_text(text)
    path = write(tmp_path / "arm2.json", arm_file({"link": {"file": "parts/link.json"}}))
    refused(path, "definitions.link: parts/link.json: ports.axis \"joint.ax\": Revolute "
                  "'joint' has no port 'ax'")


def test_problems_inside_a_definition_name_their_place(tmp_path):
    link = inline_link()
    link["components"][2]["params"]["mass"] = -1
    link["components"][0]["params"]["axs"] = [0, 0, 1]
    path = write(tmp_path / "arm.json", arm_file({"link": link}))
    refused(path, 'definitions.link.components[2] "bob" params.mass = -1 kg: must be >= 0',
            'definitions.link.components[0] "joint" params.axs: unknown parameter')
    # a value given to one instance that breaks a part inside: the instance path, then the
    # place of the part in the file
    data = arm_file({"link": inline_link()})
    data["components"][2]["params"]["m"] = -2
    path = write(tmp_path / "arm2.json", data)
    refused(path, 'lower/bob.mass (definitions.link.components[2] "bob" params.mass) = -2.0 '
                  'kg: must be >= 0')


@pytest.mark.parametrize("definitions, message", [
    ([1, 2], "definitions: must be an object of definitions by name"),
    ({"Probe": {"components": []}}, "Probe: a kinetwork component type has this name"),
    ({"link": 3}, "definitions.link: must be an object"),
    ({"link": {"file": "x.json", "extra": 1}}, "a reference has only the key 'file'"),
    ({"link": {"components": [], "simulation": {}}}, "definitions.link: unknown key "
                                                      "'simulation'"),
    ({"link": {"file": "missing.json"}}, "cannot read the file"),
])
def test_malformed_definitions_are_refused(tmp_path, definitions, message):
    path = write(tmp_path / "arm.json", arm_file(definitions))
    refused(path, message)


def test_a_definition_file_must_hold_the_model_it_is_named_for(tmp_path):
    other = link_model()
    other.name = "rod"
    save(other, tmp_path / "link.json")
    path = write(tmp_path / "arm.json", arm_file({"link": {"file": "link.json"}}))
    refused(path, "holds model 'rod', not 'link'")


def test_version_1_files_keep_their_keys(tmp_path, seed_model):
    data = json.loads(kn.dumps(seed_model))
    data["definitions"] = {}
    path = write(tmp_path / "m.json", data)
    refused(path, "'definitions': unknown key", "need version 2")


@pytest.mark.parametrize("name", ["my link", "Probe", "link.v2"])
def test_a_definition_a_file_cannot_name_is_refused_at_saving(tmp_path, name):
    link = link_model()
    link.name = name
    arm = kn.Model("arm")
    arm.add(kn.Subsystem("upper", link))
    with pytest.raises(kn.ModelError, match="a definition's name is the type its instances "
                                            "have in a file"):
        arm.save(tmp_path / "arm.json")
    assert not (tmp_path / "arm.json").exists()


def test_run_sets_a_subsystem_value_by_path(tmp_path, capsys):
    path = tmp_path / "arm.json"
    seed_of_links().save(path)
    assert main(["run", str(path), "--t-end", "0.1", "-q", "--param", "upper.q0=0.3",
                 "--param", "c=2", "--out", str(tmp_path / "out.csv")]) == 0
    first = (tmp_path / "out.csv").read_text().splitlines()[1].split(",")
    assert float(first[1]) == pytest.approx(0.3)
    assert main(["run", str(path), "--t-end", "0.1", "-q", "--param", "nope.q0=0.3"]) == 1
    assert "a path names a parameter of a subsystem placed in 'arm'" in capsys.readouterr().err


def test_a_definition_file_that_is_no_json_says_where(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "link.json").write_text('{"format": "kinetwork.model",\n  "name": }')
    path = write(tmp_path / "arm.json", arm_file({"link": {"file": "parts/link.json"}}))
    refused(path, "definitions.link: parts/link.json: line 2 column 11: invalid JSON")
