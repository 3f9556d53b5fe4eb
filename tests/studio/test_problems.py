"""How the studio server sends a problem to the page: by the fields of its record
(``kinetwork.Problem``: component, port, parameter, path, hint, severity), never by reading
the message to place it; the message is read only for ``reason``, what is wrong without the
place its fields name.
"""

import pytest

from kinetwork.errors import ModelError, Problem
from kinetwork.studio import checks


def test_a_record_is_placed_by_its_fields_and_said_without_its_place():
    record = Problem('components[4] "mass1" params.mass = -1 kg: must be >= 0',
                    component="mass1", parameter="mass", path="components[4].params.mass")
    out = checks.problem(record)
    assert (out["component"], out["parameter"], out["param"], out["path"]) == \
        ("mass1", "mass", "mass", "components[4].params.mass")
    assert out["reason"] == "must be >= 0 (got -1 kg)"
    assert out["severity"] == "error" and out["connection"] is None


def test_a_reworded_message_moves_no_marker():
    record = Problem("the mass of the second link is negative", component="mass1",
                    parameter="mass", path="components[4].params.mass", hint="use 1 kg")
    out = checks.problem(record)
    assert (out["component"], out["parameter"], out["hint"]) == ("mass1", "mass", "use 1 kg")
    assert out["reason"] is None          # the page shows the whole message
    assert out["message"] == "the mass of the second link is negative"


def test_fields_win_over_a_message_that_names_another_place():
    record = Problem('components[0] "ground": looks wrong', component="link1",
                    path="components[2]", severity="warning")
    out = checks.problem(record)
    assert (out["component"], out["path"], out["severity"]) == \
        ("link1", "components[2]", "warning")
    assert out["reason"] is None


@pytest.mark.parametrize("path, connection", [("connections[3]", 3),
                                              ("connections[3][1]", 3),
                                              ("definitions.Arm.connections[1]", None)])
def test_a_wire_problem_is_on_its_wire(path, connection):
    out = checks.problem(Problem("connections[3]: frame_a and axis are different domains",
                                path=path))
    assert out["connection"] == connection and out["component"] is None
    assert out["reason"] == ("frame_a and axis are different domains" if connection
                             else None)


def test_a_port_problem_is_on_its_block():
    out = checks.problem(Problem("shoulder.frame_b: not connected", component="shoulder",
                                port="frame_b"))
    assert (out["component"], out["port"], out["reason"]) == \
        ("shoulder", "frame_b", "not connected")


def test_a_plain_string_has_no_place():
    # the message names a place, but no field does: nothing is guessed from the text
    out = checks.problem('components[4] "mass1" params.mass = -1 kg: must be >= 0')
    assert (out["component"], out["parameter"], out["path"], out["connection"]) == \
        (None, None, None, None)
    assert out["reason"] is None and out["severity"] == "error"


def test_at_most_MAX_PROBLEMS_are_sent_and_the_rest_counted():
    many = ModelError([Problem(f"components[{i}] \"b{i}\": not connected", component=f"b{i}",
                               path=f"components[{i}]") for i in range(checks.MAX_PROBLEMS + 7)])
    out = checks.problems_of(many)
    assert len(out) == checks.MAX_PROBLEMS + 1
    assert out[0]["component"] == "b0" and out[0]["reason"] == "not connected"
    assert "7 more problems" in out[-1]["message"] and out[-1]["component"] is None
