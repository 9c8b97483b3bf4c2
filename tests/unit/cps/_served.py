"""The AAS each asset of a floor serves, as its node builds it for its OPC UA server (the
demo floor on the emulated plant, whose physical units add `RunTransfer`, and the large
floor): shared by the AAS conformance and ontology tests."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from transfertwin.cps.aas import AssetRepresentation, build_representation, operation
from transfertwin.cps.floor import PROVENANCE, default_floor_spec, load_floor
from transfertwin.cps.node import lifecycle_submodel
from transfertwin.cps.roles import RUN_TRANSFER

ROOT = Path(__file__).resolve().parents[3]


def served(floor) -> list[AssetRepresentation]:
    """Each asset's AAS as its node serves it: endpoint and provenance in Identification, a
    plant unit's `RunTransfer` in its ControlInterface, and the process's `Lifecycle`
    submodel (`Shutdown`) beside the AAS's."""
    reps = []
    for port, desc in enumerate(floor.descriptors(), start=4840):
        hal, _ = floor.hal_of(desc.asset_id)
        rep = build_representation(
            desc,
            endpoint=f"opc.tcp://127.0.0.1:{port}/transfertwin/{desc.asset_id}",
            provenance=PROVENANCE[hal],
        )
        if desc.asset_id.endswith("_P"):
            rep.submodel("ControlInterface").submodel_element.add(operation(RUN_TRANSFER))
        rep = dataclasses.replace(rep, submodels=(*rep.submodels,
                                                  lifecycle_submodel(desc.asset_id)))
        reps.append(rep)
    return reps


FLOORS = {
    "demo-plant": lambda: default_floor_spec().with_hal("plant"),
    "large": lambda: load_floor(ROOT / "examples" / "floor-large.toml", check_cores=False),
}
