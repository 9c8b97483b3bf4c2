"""AAS virtual representations (Sec. 3.1–3.2, Table 3.1, Sec. 5.1–5.3).

Expected idShorts, value types and operation arguments are written out here from the
design brief, not read from the spec tables under test.
"""

from __future__ import annotations

import pytest
from basyx.aas import model

from transfertwin._errors import InputError
from transfertwin.cps.aas._assets import AssetDescriptor, AssetKind, Capability, PhysicalType
from transfertwin.cps.aas._demo import demo_descriptors, physical_twin
from transfertwin.cps.aas._representation import (
    AssetRepresentation,
    build_representation,
    externally_synced,
)
from transfertwin.cps.aas._spec import (
    CONTROL_INTERFACE,
    LOGICAL_CLASSES,
    OPERATIONAL_DATA,
    PHYSICAL_CLASSES,
)

DEMO = {d.asset_id: d for d in demo_descriptors()}

BELTS = [
    "BeltSpeedLeft",
    "BeltSpeedRight",
    "BarrierNearInterrupted",
    "BarrierFarInterrupted",
    "PossessedObjects",
]
EXPECTED_ELEMENTS = {
    "TU_A": {
        "Identification": [
            "AssetId", "AssetClass", "AssetKind", "PhysicalType", "Station", "Provenance",
            "ModelOf",
        ],
        "Capabilities": ["Transfer", "TransferRelations", "Sense", "SenseRelations"],
        "OperationalData": [*BELTS, "DockedTransportModule"],
        "ControlInterface": ["SetBeltSpeed", "SetPossessedObjects"],
    },
    "TM_1": {
        "Identification": [
            "AssetId", "AssetClass", "AssetKind", "PhysicalType", "Provenance", "ModelOf",
        ],
        "Capabilities": ["Transport", "TransportRelations", "Transfer", "TransferRelations",
                         "Sense", "SenseRelations"],
        "OperationalData": [
            *BELTS, "PoseX", "PoseY", "PoseTheta", "DockedAt", "State", "CurrentTask",
        ],
        "ControlInterface": [
            "SetBeltSpeed", "Dock", "Undock", "ReleaseObject", "AssignOperation", "Bid",
        ],
    },
    "o5": {
        "Identification": [
            "AssetId", "AssetClass", "AssetKind", "PhysicalType", "Provenance", "ModelOf",
        ],
        "Capabilities": [],
        "OperationalData": ["PossessedBy", "Face", "Conveyor", "Theta", "LastTransfer",
                            "TransferHistoryJson", "PredictionsJson"],
    },
    "TMS": {
        "Identification": ["AssetId", "AssetClass", "AssetKind", "Provenance"],
        "Capabilities": ["Allocate", "AllocateRelations"],
        "OperationalData": ["State", "QueuedOperations", "CompletedOperations", "Policy",
                            "OperationsPerHour", "SuccessShare", "SuccessShareLow",
                            "SuccessShareHigh", "MeanLeadTime", "KpisJson"],
        "ControlInterface": [
            "SubmitTransportOperation", "OrderTo", "Orders", "Kpis", "OperationStatus",
            "ReportProgress", "Ledger", "Locate",
        ],
    },
    "EM": {
        "Identification": ["AssetId", "AssetClass", "AssetKind", "Provenance"],
        "Capabilities": ["Experiment", "ExperimentRelations"],
        "OperationalData": ["State", "ExperimentsDone", "StudyState", "StudyPlan",
                            "StudyStore", "StudyDone", "StudyPlanned", "StudyProgress",
                            "StudyRate", "StudyEtaS", "CampaignProgress"],
        "ControlInterface": ["RunExperiment", "Predict", "StartStudy", "StopStudy",
                             "StudyStatus", "StartCampaign", "StopCampaign", "CampaignStatus"],
    },
    "PropS": {
        "Identification": ["AssetId", "AssetClass", "AssetKind", "Provenance"],
        "Capabilities": ["FusePoses", "FusePosesRelations"],
        "OperationalData": ["State", "FusedPoses", "FusedPosesJson", "DockingErrorsJson"],
        "ControlInterface": ["ReportPose", "ReportRelativePose", "DockingError", "FusedPose"],
    },
    "KG": {
        "Identification": ["AssetId", "AssetClass", "AssetKind", "Provenance"],
        "Capabilities": ["Knowledge", "KnowledgeRelations"],
        "OperationalData": ["State", "Triples", "Assets"],
        "ControlInterface": ["Query", "Heartbeat", "Leave", "Status"],
    },
}  # fmt: skip

_S, _D, _B, _I = "xs:string", "xs:double", "xs:boolean", "xs:int"
EXPECTED_OPERATIONS = [
    ("TU_A", "SetBeltSpeed", [("belt", _S), ("speed", _D)], [("ok", _B)]),
    ("TU_A", "SetPossessedObjects", [("objects", _S)], [("ok", _B)]),
    ("TM_1", "SetBeltSpeed", [("belt", _S), ("speed", _D)], [("ok", _B)]),
    ("TM_1", "Dock", [("unit", _S)], [("ok", _B)]),
    ("TM_1", "Undock", [], [("ok", _B)]),
    ("TMS", "SubmitTransportOperation", [("source", _S), ("target", _S), ("object", _S)],
     [("operation_id", _S)]),
    ("TMS", "OperationStatus", [("operation_id", _S)], [("status_json", _S)]),
    ("EM", "RunExperiment",
     [("unit", _S), ("object", _S), ("face", _S), ("conveyor", _S), ("theta_deg", _I),
      ("seed", _I)],
     [("result_json", _S)]),
    ("EM", "Predict", [("object", _S), ("runs", _I), ("seed", _I)], [("predictions_json", _S)]),
    ("PropS", "ReportPose",
     [("source", _S), ("subject", _S), ("x_m", _D), ("y_m", _D), ("theta_rad", _D),
      ("sigma_xy", _D), ("sigma_theta", _D)],
     [("ok", _B)]),
    ("EM", "StartStudy", [("plan_json", _S), ("store", _S)], [("status_json", _S)]),
    ("EM", "StopStudy", [], [("status_json", _S)]),
    ("EM", "StudyStatus", [], [("status_json", _S)]),
    ("PropS", "FusedPose", [("subject", _S)], [("pose_json", _S)]),
    ("PropS", "ReportRelativePose",
     [("source", _S), ("subject", _S), ("relative_to", _S), ("x_m", _D), ("y_m", _D),
      ("theta_rad", _D), ("sigma_xy", _D), ("sigma_theta", _D)], [("ok", _B)]),
    ("PropS", "DockingError", [("module", _S), ("unit", _S)], [("estimate_json", _S)]),
    ("KG", "Query", [("sparql", _S)], [("result_json", _S)]),
    # one process per asset (docs/architecture.md, "Deployment")
    ("TM_1", "AssignOperation",
     [("operation_id", _S), ("source", _S), ("target", _S), ("object", _S),
      ("plan_json", _S)], [("ok", _B)]),
    ("TM_1", "Bid", [("order_json", _S)], [("bid_json", _S)]),
    # operations that use the twin (docs/architecture.md, "Operation")
    ("TMS", "OrderTo", [("object", _S), ("destination", _S)], [("operation_id", _S)]),
    ("TMS", "Orders", [], [("orders_json", _S)]),
    ("TMS", "Kpis", [], [("kpis_json", _S)]),
    ("TMS", "ReportProgress", [("operation_id", _S), ("event_json", _S)], [("ok", _B)]),
    ("TMS", "Ledger", [], [("ledger_json", _S)]),
    ("TMS", "Locate", [("object", _S), ("holder", _S)], [("ok", _B)]),
    ("KG", "Heartbeat", [("heartbeat_json", _S)], [("directory_json", _S)]),
    ("KG", "Leave", [("asset_id", _S)], [("ok", _B)]),
    ("KG", "Status", [], [("status_json", _S)]),
]  # fmt: skip


def xsd(element: model.Property) -> str:
    return model.datatypes.XSD_TYPE_NAMES[element.value_type]


def unit(element: model.Property) -> str | None:
    units = [q.value for q in element.qualifier if q.type == "Unit"]
    return units[0] if units else None


def element_names(rep: AssetRepresentation) -> dict[str, list[str]]:
    return {sm.id_short: [e.id_short for e in sm.submodel_element] for sm in rep.submodels}


@pytest.mark.parametrize("asset_id", list(DEMO))
def test_every_demo_asset_builds_with_iri_identifiers(asset_id: str) -> None:
    rep = build_representation(DEMO[asset_id])
    assert rep.shell.id == f"https://transfertwin.dev/ids/aas/{asset_id}"
    assert rep.shell.id_short == asset_id
    info = rep.shell.asset_information
    assert info.asset_kind is model.AssetKind.INSTANCE
    assert info.global_asset_id == f"https://transfertwin.dev/ids/asset/{asset_id}"
    referenced = {ref.key[-1].value for ref in rep.shell.submodel}
    assert referenced == {sm.id for sm in rep.submodels}
    for sm in rep.submodels:
        assert sm.id == f"https://transfertwin.dev/ids/sm/{asset_id}/{sm.id_short}"
    assert len(rep.object_store()) == 1 + len(rep.submodels)


def test_demo_cps_has_the_assets_of_sec_5_3() -> None:
    assert list(DEMO) == [
        "TU_A", "TU_B", "TU_C", "TU_D", "TM_1", "o1", "o2", "o3", "o4", "o5",
        "TMS", "EM", "PropS", "KG",
    ]  # fmt: skip
    assert [DEMO[f"TU_{s}"].station for s in "ABCD"] == ["A", "B", "C", "D"]
    assert DEMO["TU_B"].physical_type is PhysicalType.D_E
    assert DEMO["TM_1"].physical_type is PhysicalType.E
    assert DEMO["o3"].physical_type is PhysicalType.B
    assert DEMO["o3"].models == "o3_P"
    assert {DEMO[a].kind for a in ("TMS", "EM", "PropS", "KG")} == {AssetKind.LOGICAL}


@pytest.mark.parametrize("asset_id", list(EXPECTED_ELEMENTS))
def test_submodel_element_idshorts_per_asset_class(asset_id: str) -> None:
    assert element_names(build_representation(DEMO[asset_id])) == EXPECTED_ELEMENTS[asset_id]


@pytest.mark.parametrize(("asset_id", "op", "inputs", "outputs"), EXPECTED_OPERATIONS)
def test_operation_arguments_as_specified(
    asset_id: str, op: str, inputs: list[tuple[str, str]], outputs: list[tuple[str, str]]
) -> None:
    operation = build_representation(DEMO[asset_id]).operation(op)
    assert [(v.id_short, xsd(v)) for v in operation.input_variable] == inputs
    assert [(v.id_short, xsd(v)) for v in operation.output_variable] == outputs
    assert list(operation.in_output_variable) == []


@pytest.mark.parametrize(
    ("asset_id", "prop", "value_type", "unit_", "initial"),
    [
        ("TU_A", "BeltSpeedLeft", _D, "m/s", 0.0),
        ("TU_A", "BarrierFarInterrupted", _B, None, False),
        ("TU_A", "PossessedObjects", _S, None, ""),
        ("TU_A", "DockedTransportModule", _S, None, ""),
        ("TM_1", "PoseY", _D, "m", 0.0),
        ("TM_1", "PoseTheta", _D, "rad", 0.0),
        ("TM_1", "State", _S, None, "idle"),
        ("o1", "Theta", _D, "rad", 0.0),
        ("o1", "PossessedBy", _S, None, ""),
        ("TMS", "QueuedOperations", _I, None, 0),
        ("KG", "Triples", _I, None, 0),
    ],
)
def test_operational_data_types_units_and_initial_values(
    asset_id: str, prop: str, value_type: str, unit_: str | None, initial: object
) -> None:
    element = build_representation(DEMO[asset_id]).property("OperationalData", prop)
    assert (xsd(element), unit(element), element.value) == (value_type, unit_, initial)


def test_unit_of_operation_argument_is_a_qualifier() -> None:
    op = build_representation(DEMO["PropS"]).operation("ReportPose")
    units = {v.id_short: unit(v) for v in op.input_variable}
    assert units == {
        "source": None,
        "subject": None,
        "x_m": "m",
        "y_m": "m",
        "theta_rad": "rad",
        "sigma_xy": "m",
        "sigma_theta": "rad",
    }


def test_type_b_object_has_no_control_interface() -> None:
    rep = build_representation(DEMO["o5"])
    assert "ControlInterface" not in element_names(rep)
    with pytest.raises(InputError, match="no submodel 'ControlInterface'"):
        rep.operation("SetBeltSpeed")


@pytest.mark.parametrize(
    ("ptype", "operations"),
    [
        (PhysicalType.C, None),  # Table 3.1: no control interface
        (PhysicalType.D, ["SetBeltSpeed", "SetPossessedObjects"]),  # external sync
        (PhysicalType.E, ["SetBeltSpeed"]),  # internal sync: nothing to set from outside
    ],
)
def test_control_interface_follows_table_3_1(ptype: PhysicalType, operations: list | None) -> None:
    desc = AssetDescriptor("TU_X", AssetKind.PHYSICAL, "transfer_unit", physical_type=ptype)
    assert element_names(build_representation(desc)).get("ControlInterface") == operations


def test_externally_synced_properties_follow_table_3_1() -> None:
    reps = {a: build_representation(DEMO[a]) for a in ("TU_A", "TM_1", "o1", "PropS")}
    assert externally_synced(reps["TU_A"]) == {"PossessedObjects", "DockedTransportModule"}
    assert externally_synced(reps["o1"]) == {"PossessedBy", "Face", "Conveyor", "Theta",
                                             "LastTransfer", "TransferHistoryJson",
                                             "PredictionsJson"}  # fmt: skip
    assert externally_synced(reps["TM_1"]) == frozenset()
    assert externally_synced(reps["PropS"]) == frozenset()


def test_type_a_asset_has_no_representation() -> None:
    pillar = AssetDescriptor("Pillar", AssetKind.PHYSICAL, "object", physical_type=PhysicalType.A)
    with pytest.raises(InputError, match="type A"):
        build_representation(pillar)


@pytest.mark.parametrize("bad_id", ["_TU", "1TU", "TÜ_A", "TU-A", "", "TU A"])
def test_invalid_asset_id_is_refused(bad_id: str) -> None:
    with pytest.raises(InputError):
        desc = AssetDescriptor(bad_id, AssetKind.LOGICAL, "props")
        build_representation(desc)


@pytest.mark.parametrize(
    ("kind", "asset_class", "ptype"),
    [
        (AssetKind.LOGICAL, "transfer_unit", None),
        (AssetKind.PHYSICAL, "props", PhysicalType.E),
        (AssetKind.PHYSICAL, "conveyor", PhysicalType.D),
    ],
)
def test_asset_class_must_fit_kind(kind: AssetKind, asset_class: str, ptype) -> None:
    with pytest.raises(InputError, match="does not fit kind"):
        build_representation(AssetDescriptor("X1", kind, asset_class, physical_type=ptype))


def test_capabilities_carry_ontology_semantic_ids() -> None:
    caps = build_representation(DEMO["PropS"]).submodel("Capabilities").submodel_element
    (fuse,) = [c for c in caps if isinstance(c, model.Capability)]
    assert isinstance(fuse, model.Capability)
    assert fuse.id_short == "FusePoses"
    assert fuse.semantic_id.key[0].value == "https://transfertwin.dev/ontology#FusePoses"


def test_every_capability_gets_a_valid_idshort() -> None:
    desc = AssetDescriptor("All", AssetKind.LOGICAL, "props", capabilities=tuple(Capability))
    caps = build_representation(desc).submodel("Capabilities").submodel_element
    names = [c.id_short for c in caps if isinstance(c, model.Capability)]
    assert names == [
        "Transfer", "Transport", "Sense", "Allocate", "Experiment", "FusePoses", "Knowledge",
    ]  # fmt: skip


def test_identification_values_of_a_virtual_and_a_logical_asset() -> None:
    tu = build_representation(DEMO["TU_C"], endpoint="opc.tcp://127.0.0.1:4841/tu_c")
    values = {p.id_short: p.value for p in tu.submodel("Identification").submodel_element}
    assert values == {
        "AssetId": "TU_C",
        "AssetClass": "transfer_unit",
        "AssetKind": "virtual_model",
        "PhysicalType": "D/E",
        "Station": "C",
        "Provenance": "virtual",
        "ModelOf": "TU_C_P",
        "Endpoint": "opc.tcp://127.0.0.1:4841/tu_c",
    }
    kg = build_representation(DEMO["KG"])
    assert kg.property("Identification", "Provenance").value == "logical"


def test_provenance_detail_is_the_description_of_provenance() -> None:
    rep = build_representation(DEMO["TM_1"], provenance="mujoco; calibration run 7")
    prov = rep.property("Identification", "Provenance")
    assert (prov.value, prov.description["en"]) == ("virtual", "mujoco; calibration run 7")


@pytest.mark.parametrize("kwargs", [{"endpoint": "http://localhost:4840"}, {"provenance": "  "}])
def test_bad_endpoint_or_blank_provenance_is_refused(kwargs: dict[str, str]) -> None:
    with pytest.raises(InputError):
        build_representation(DEMO["TU_A"], **kwargs)


def test_lookup_errors_are_one_line_input_errors() -> None:
    rep = build_representation(DEMO["TU_A"])
    with pytest.raises(InputError, match="no element 'Nope'"):
        rep.property("OperationalData", "Nope")
    with pytest.raises(InputError, match="is a Operation"):
        rep.property("ControlInterface", "SetBeltSpeed")
    with pytest.raises(InputError, match="ControlInterface has no element 'Dock'"):
        rep.operation("Dock")
    assert rep.operation("SetBeltSpeed").id_short == "SetBeltSpeed"


def test_physical_twin_of_a_virtual_model() -> None:
    twin = physical_twin(DEMO["TU_A"])
    assert (twin.asset_id, twin.kind, twin.models) == ("TU_A_P", AssetKind.PHYSICAL, None)
    assert (twin.physical_type, twin.station) == (PhysicalType.D_E, "A")
    with pytest.raises(InputError, match="not a virtual model"):
        physical_twin(twin)


def test_spec_tables_cover_every_asset_class() -> None:
    classes = PHYSICAL_CLASSES | LOGICAL_CLASSES
    assert set(OPERATIONAL_DATA) == classes
    assert set(CONTROL_INTERFACE) == classes
