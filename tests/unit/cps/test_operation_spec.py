"""The floor file's [operation] table: the TMS's policy, study store and destination groups
(docs/architecture.md, "Operation")."""

from __future__ import annotations

import dataclasses

import pytest

from transfertwin._errors import InputError
from transfertwin.cps import default_floor_spec, floor_toml, load_floor
from transfertwin.cps.floor._floor_file import OperationSpec


def _with(tmp_path, table: str):
    text = floor_toml(default_floor_spec()).split("\n[operation]")[0]
    path = tmp_path / "floor.toml"
    path.write_text(text + "\n" + table)
    return path


def test_operation_round_trips_and_a_relative_study_is_the_floor_files(tmp_path):
    (tmp_path / "s.sqlite").write_bytes(b"")
    path = _with(tmp_path, '[operation]\npolicy = "predictive"\nstudy = "s.sqlite"\nruns = 3\n'
                           'capacity = 1\nsensor = "camera"\nlearn = false\n'
                           'sampling = "adaptive"\n'
                           '[operation.groups]\nout = ["TU_C", "TU_D"]\n')
    spec = load_floor(path)
    op = spec.operation
    assert (op.policy, op.runs, op.capacity, op.group("out"), op.group("TU_C")) == (
        "predictive", 3, 1, ("TU_C", "TU_D"), None)
    assert op.study == str((tmp_path / "s.sqlite").resolve()) and op.sensor == "camera"
    assert op.learn is False and op.sampling == "adaptive"
    (tmp_path / "again.toml").write_text(floor_toml(spec))
    assert load_floor(tmp_path / "again.toml") == spec


def test_the_default_is_predictive_without_a_study():
    """The floor uses the twin by default (its ranking, learnt on by the floor's own
    transfers); nearest-idle is the explicit choice of a floor file or `cps up --policy`."""
    assert default_floor_spec().operation == OperationSpec("predictive", None, 4, (), 0,
                                                           "truth", True)


@pytest.mark.parametrize(("table", "message"), [
    ('[operation]\npolicy = "fastest"\n', "operation.policy must be one of"),
    ('[operation]\nruns = 0\n', "operation.runs must be 1..1000"),
    ('[operation]\nruns = "4"\n', "runs must be an integer"),
    ('[operation]\nspeed = 1\n', "unknown key 'speed'"),
    ('[operation]\ncapacity = -1\n', "capacity must be >= 0"),
    ('[operation]\nsensor = "lidar"\n', "operation.sensor must be one of truth, camera"),
    ('[operation]\nlearn = "yes"\n', "learn must be true or false"),
    ('[operation]\nsampling = "random"\n', "operation.sampling must be one of exhaustive"),
    ('[operation.groups]\nout = ["TU_Z"]\n', "must list transfer units"),
    ('[operation.groups]\nTU_A = ["TU_B"]\n', "is also an asset id"),
])
def test_a_bad_operation_table_is_one_clear_error(tmp_path, table, message):
    with pytest.raises(InputError, match=message):
        load_floor(_with(tmp_path, table))


def test_replacing_the_policy_checks_it_again():
    with pytest.raises(InputError, match="policy"):
        dataclasses.replace(default_floor_spec(),
                            operation=OperationSpec(policy="random"))  # fmt: skip
