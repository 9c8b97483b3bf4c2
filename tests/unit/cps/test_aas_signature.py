"""A virtual model is structured like its physical twin (Sec. 3.2, Fig. 3.3b)."""

from __future__ import annotations

import pytest
from basyx.aas import model

from transfertwin.cps.aas._assets import AssetKind
from transfertwin.cps.aas._demo import demo_descriptors, physical_twin
from transfertwin.cps.aas._representation import build_representation, wire_signature

DEMO = {d.asset_id: d for d in demo_descriptors()}
VIRTUAL = [a for a, d in DEMO.items() if d.kind is AssetKind.VIRTUAL_MODEL]


def test_virtual_and_physical_transfer_unit_share_the_wire_signature() -> None:
    virtual = build_representation(DEMO["TU_A"], endpoint="opc.tcp://127.0.0.1:4841/v")
    physical = build_representation(physical_twin(DEMO["TU_A"]))
    assert wire_signature(virtual) == wire_signature(physical)
    # ... and they differ only in the provenance part of Identification
    ident_v = {p.id_short: p.value for p in virtual.submodel("Identification").submodel_element}
    ident_p = {p.id_short: p.value for p in physical.submodel("Identification").submodel_element}
    assert set(ident_v) - set(ident_p) == {"ModelOf", "Endpoint"}
    assert (ident_v["Provenance"], ident_p["Provenance"]) == ("virtual", "physical")
    assert ident_v["ModelOf"] == physical.descriptor.asset_id == "TU_A_P"
    assert virtual.shell.id != physical.shell.id


@pytest.mark.parametrize("asset_id", VIRTUAL)
def test_every_demo_virtual_model_matches_its_physical_twin(asset_id: str) -> None:
    desc = DEMO[asset_id]
    assert wire_signature(build_representation(desc)) == wire_signature(
        build_representation(physical_twin(desc))
    )


def test_signature_ignores_values_and_instance_ids() -> None:
    a, b = build_representation(DEMO["TU_A"]), build_representation(DEMO["TU_B"])
    b.property("OperationalData", "BeltSpeedLeft").value = 0.12
    assert wire_signature(a) == wire_signature(b)


def test_signature_tells_asset_classes_apart() -> None:
    tu, tm = build_representation(DEMO["TU_A"]), build_representation(DEMO["TM_1"])
    assert wire_signature(tu) != wire_signature(tm)


def test_signature_sees_a_changed_value_type() -> None:
    a, b = build_representation(DEMO["TU_A"]), build_representation(DEMO["TU_A"])
    sm = b.submodel("OperationalData")
    sm.remove_referable("BeltSpeedLeft")
    sm.submodel_element.add(model.Property("BeltSpeedLeft", model.datatypes.Float, 0.0))
    assert wire_signature(a) != wire_signature(b)


def test_signature_sees_a_changed_operation_argument() -> None:
    a, b = build_representation(DEMO["TM_1"]), build_representation(DEMO["TM_1"])
    dock = b.operation("Dock")
    dock.input_variable.add(model.Property("face", model.datatypes.String))
    assert wire_signature(a) != wire_signature(b)


def test_signature_sees_a_missing_capability() -> None:
    a = build_representation(DEMO["TM_1"])
    b = build_representation(physical_twin(DEMO["TM_1"]))
    b.submodel("Capabilities").remove_referable("Sense")
    assert wire_signature(a) != wire_signature(b)
