"""What the assets' roles are built from, as libraries: the object ledger, the pose graph
PropS fuses (`PoseGraph`), the transport operation flow (Fig. 5.9a) and the hand-over
policy, the module's drive on the shop floor (`FloorRobot`), the camera's check of what it
sees, the simulated environment, the docking-error model, and studies run by the
Experiment Manager (`StudyJob`) and its calibration campaigns on the floor (`CampaignJob`).

The names load on first use (PEP 562): an asset process imports only what its role needs
(a unit or an object needs neither the simulation nor the navigation stack).
"""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.cps.apps._camera import ScanVerdict, height_key, scan_check
    from transfertwin.cps.apps._campaign import (
        CAMPAIGN_MEASURES,
        CampaignJob,
        CampaignRequest,
        CampaignStoppedError,
        FloorPlant,
        UnitUnavailableError,
    )
    from transfertwin.cps.apps._docking import docking_model
    from transfertwin.cps.apps._environment import Environment, ScaledClock
    from transfertwin.cps.apps._floor import HOME_POSE, FloorRobot, LegResult
    from transfertwin.cps.apps._hand_over import (
        DEFAULT_STATE,
        DELIVERY_RETRIES,
        PICKUP_RETRIES,
        HandOverRetries,
        state_text,
        take_back,
    )
    from transfertwin.cps.apps._ledger import ObjectLedger
    from transfertwin.cps.apps._props import (
        Pose2D,
        PoseGraph,
        PoseGraphSolution,
        PoseObservation,
        fuse_poses,
        wrap_angle,
    )
    from transfertwin.cps.apps._study_job import (
        STUDY_INDEX,
        StudyJob,
        StudyRequest,
        record_store,
        study_opcua_values,
        study_stores,
    )
    from transfertwin.cps.apps._transport import (
        STEPS,
        Leg,
        OtsCheck,
        StepResult,
        TransportSkills,
        form_ots,
        legs_of,
        run_transport_operation,
        transfer_step,
    )

__all__ = [
    "CAMPAIGN_MEASURES",
    "DEFAULT_STATE",
    "DELIVERY_RETRIES",
    "HOME_POSE",
    "PICKUP_RETRIES",
    "STEPS",
    "STUDY_INDEX",
    "CampaignJob",
    "CampaignRequest",
    "CampaignStoppedError",
    "Environment",
    "FloorPlant",
    "FloorRobot",
    "HandOverRetries",
    "Leg",
    "LegResult",
    "ObjectLedger",
    "OtsCheck",
    "Pose2D",
    "PoseGraph",
    "PoseGraphSolution",
    "PoseObservation",
    "ScaledClock",
    "ScanVerdict",
    "StepResult",
    "StudyJob",
    "StudyRequest",
    "TransportSkills",
    "UnitUnavailableError",
    "docking_model",
    "form_ots",
    "fuse_poses",
    "height_key",
    "legs_of",
    "record_store",
    "run_transport_operation",
    "scan_check",
    "state_text",
    "study_opcua_values",
    "study_stores",
    "take_back",
    "transfer_step",
    "wrap_angle",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
