"""How the studio server sends a problem to the page: by the fields of its record when the
library gives them (``kinetwork.Problem``: component, port, parameter, path, hint,
severity), never by reading the message to place it; a plain string is still placed.

``Record`` stands for the library's ``Problem`` (a ``str`` with those fields), so these
tests hold before and after the library's records land.
"""

import pytest

from kinetwork.studio import checks


class Record(str):
    """A message with the fields of a ``kinetwork.Problem``."""

    def __new__(cls, message, component=None, port=None, parameter=None, path=None,
                hint=None, severity="error"):
        self = super().__new__(cls, message)
        self.component, self.port, self.parameter = component, port, parameter
        self.path, self.hint, self.severity = path, hint, severity
        return self


def test_a_record_is_placed_by_its_fields_and_said_without_its_place():
    record = Record('components[4] "mass1" params.mass = -1 kg: must be >= 0',
                    component="mass1", parameter="mass", path="components[4].params.mass")
    out = checks.problem(record)
    assert (out["component"], out["parameter"], out["param"], out["path"]) == \
        ("mass1", "mass", "mass", "components[4].params.mass")
    assert out["reason"] == "must be >= 0 (got -1 kg)"
    assert out["severity"] == "error" and out["connection"] is None


def test_a_reworded_message_moves_no_marker():
    record = Record("the mass of the second link is negative", component="mass1",
                    parameter="mass", path="components[4].params.mass", hint="use 1 kg")
    out = checks.problem(record)
    assert (out["component"], out["parameter"], out["hint"]) == ("mass1", "mass", "use 1 kg")
    assert out["reason"] is None          # the page shows the whole message
    assert out["message"] == "the mass of the second link is negative"


def test_fields_win_over_a_message_that_names_another_place():
    record = Record('components[0] "ground": looks wrong', component="link1",
                    path="components[2]", severity="warning")
    out = checks.problem(record, names=["ground", "shoulder", "link1"])
    assert (out["component"], out["path"], out["severity"]) == \
        ("link1", "components[2]", "warning")
    assert out["reason"] is None


@pytest.mark.parametrize("path, connection", [("connections[3]", 3),
                                              ("connections[3][1]", 3),
                                              ("definitions.Arm.connections[1]", None)])
def test_a_wire_problem_is_on_its_wire(path, connection):
    out = checks.problem(Record("connections[3]: frame_a and axis are different domains",
                                path=path))
    assert out["connection"] == connection and out["component"] is None
    assert out["reason"] == ("frame_a and axis are different domains" if connection
                             else None)


def test_a_port_problem_is_on_its_block():
    out = checks.problem(Record("shoulder.frame_b: not connected", component="shoulder",
                                port="frame_b"))
    assert (out["component"], out["port"], out["reason"]) == \
        ("shoulder", "frame_b", "not connected")


def test_a_plain_string_is_still_placed():
    out = checks.problem('components[4] "mass1" params.mass = -1 kg: must be >= 0')
    assert (out["component"], out["parameter"], out["path"]) == \
        ("mass1", "mass", "components[4].params.mass")
    assert out["reason"] == "must be >= 0 (got -1 kg)"
