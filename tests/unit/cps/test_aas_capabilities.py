"""Capabilities that name their operations (the IDTA capability pattern): beside each
Capability element a ``<name>Relations`` collection with a ``RealizedBy…`` relationship
from the capability to each element that realises it, and its constraints as properties.

The constraints are checked against the sources they state: the simulation's belt layout,
the built-in cores' masses, the study's pre-transfer states (not the table under test).
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from basyx.aas import model

from transfertwin.cps.aas import (
    CAPABILITY_SPECS,
    AssetRepresentation,
    Capability,
    build_representation,
    demo_descriptors,
)
from transfertwin.objects import core_spec
from transfertwin.ots import CONVEYORS, FACES, THETA_ALL
from transfertwin.sim import LayoutConfig

DEMO = {d.asset_id: d for d in demo_descriptors()}
WITH_CAPABILITIES = [a for a, d in DEMO.items() if d.capabilities]


def resolve(rep: AssetRepresentation, ref: model.ModelReference) -> model.SubmodelElement:
    """The element a reference names, looked up by the submodel's id and the idShort."""
    sm_key, el_key = ref.key
    assert sm_key.type is model.KeyTypes.SUBMODEL
    (submodel,) = [sm for sm in rep.submodels if sm.id == sm_key.value]
    element = submodel.get_referable(el_key.value)
    assert model.KeyTypes[type(element).__name__.upper()] is el_key.type
    return element


def relations(rep: AssetRepresentation, name: str) -> model.SubmodelElementCollection:
    element = rep.submodel("Capabilities").get_referable(f"{name}Relations")
    assert isinstance(element, model.SubmodelElementCollection)
    return element


def constraints(rep: AssetRepresentation, name: str) -> dict[str, object]:
    found = relations(rep, name).get_referable("Constraints")
    return {p.id_short: p.value for p in found.value}


@pytest.mark.parametrize("asset_id", WITH_CAPABILITIES)
def test_every_capability_is_realised_by_elements_the_asset_has(asset_id: str) -> None:
    rep = build_representation(DEMO[asset_id])
    caps = [e for e in rep.submodel("Capabilities").submodel_element
            if isinstance(e, model.Capability)]  # fmt: skip
    assert [c.id_short for c in caps] == [
        "".join(p.capitalize() for p in c.value.split("_")) for c in DEMO[asset_id].capabilities
    ]
    for cap in caps:
        realised = [r for r in relations(rep, cap.id_short).value
                    if isinstance(r, model.RelationshipElement)]  # fmt: skip
        assert realised, cap.id_short
        for rel in realised:
            assert resolve(rep, rel.first) is cap
            target = resolve(rep, rel.second)
            assert rel.id_short == f"RealizedBy{target.id_short}"
            assert rel.semantic_id.key[0].value.endswith("#realizedBy")
            assert isinstance(target, model.Operation | model.Property)


def test_what_realises_each_capability() -> None:
    def targets(asset_id: str, name: str) -> list[str]:
        rep = build_representation(DEMO[asset_id])
        return [resolve(rep, r.second).id_short for r in relations(rep, name).value
                if isinstance(r, model.RelationshipElement)]  # fmt: skip

    assert targets("TM_1", "Transport") == ["AssignOperation", "Bid"]
    assert targets("TM_1", "Transfer") == ["Dock", "Undock", "SetBeltSpeed"]
    assert targets("TU_A", "Transfer") == ["SetBeltSpeed"]
    assert targets("TU_A", "Sense") == ["BarrierNearInterrupted", "BarrierFarInterrupted"]
    assert targets("TMS", "Allocate") == ["SubmitTransportOperation", "OrderTo"]
    assert targets("EM", "Experiment") == ["RunExperiment", "Predict", "StartStudy",
                                           "StartCampaign"]
    assert targets("KG", "Knowledge") == ["Query"]


def test_belt_constraints_are_the_simulated_belts() -> None:
    layout = LayoutConfig()
    tu = constraints(build_representation(DEMO["TU_B"]), "Transfer")
    tm = constraints(build_representation(DEMO["TM_1"]), "Transfer")
    assert tu["BeltWidth"] == tm["BeltWidth"] == layout.belt_width_m
    assert tu["BeltLength"] == layout.tu_length_m
    assert tm["BeltLength"] == layout.tm_length_m


def test_mass_range_holds_every_built_in_core() -> None:
    masses = [core_spec(i).mass_kg for i in range(1, 38)]
    for asset_id, name in (("TU_A", "Transfer"), ("TM_1", "Transfer"), ("TM_1", "Transport")):
        c = constraints(build_representation(DEMO[asset_id]), name)
        assert c["ObjectMassMin"] <= min(masses) and max(masses) <= c["ObjectMassMax"]


def test_accepted_states_are_the_studys_pre_transfer_states() -> None:
    c = constraints(build_representation(DEMO["TM_1"]), "Transport")
    assert c["AcceptedFaces"].split(",") == list(FACES)
    assert c["AcceptedConveyors"].split(",") == list(CONVEYORS)
    assert (c["ThetaMin"], c["ThetaMax"]) == (THETA_ALL[0], THETA_ALL[-1])


def test_constraints_carry_units() -> None:
    found = relations(build_representation(DEMO["TU_A"]), "Transfer")
    units = {p.id_short: [q.value for q in p.qualifier if q.type == "Unit"]
             for p in found.get_referable("Constraints").value}  # fmt: skip
    assert units["BeltWidth"] == ["m"] and units["ObjectMassMax"] == ["kg"]
    assert units["ThetaMin"] == ["deg"] and units["AcceptedFaces"] == []


def test_a_capability_without_a_row_is_a_bare_capability() -> None:
    desc = replace(DEMO["PropS"], capabilities=(Capability.FUSE_POSES, Capability.SENSE))
    names = [e.id_short for e in
             build_representation(desc).submodel("Capabilities").submodel_element]  # fmt: skip
    assert names == ["FusePoses", "FusePosesRelations", "Sense"]
    assert "sense" not in CAPABILITY_SPECS["props"]
