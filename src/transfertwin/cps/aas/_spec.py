"""What each asset class exposes in its AAS, as plain data (Sec. 3.1, 5.1–5.3, Table 3.1).

The tables here are the functional core of the virtual representations: `_aas` turns them
into basyx objects. A virtual model uses the very same rows as its physical twin (Sec. 3.2:
"structured as identically as possible"), so the two can differ only in values and in the
provenance of the Identification submodel.

Value types are XSD names (``xs:double``, …) resolved by basyx at build time; units are
UCUM-like codes attached as a ``Unit`` qualifier.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

from transfertwin._errors import InputError
from transfertwin.cps.aas._assets import AssetDescriptor, Capability

__all__ = [
    "CAPABILITY_SPECS",
    "CONTROL_INTERFACE",
    "LOGICAL_CLASSES",
    "OPERATIONAL_DATA",
    "PHYSICAL_CLASSES",
    "Arg",
    "CapabilitySpec",
    "OperationSpec",
    "PropertySpec",
    "capability_specs",
]


@dataclass(frozen=True)
class PropertySpec:
    """One Property of the OperationalData submodel.

    Attributes:
        id_short: AAS idShort.
        xsd: XSD value type name, e.g. ``'xs:double'``.
        initial: Initial value (matching `xsd`).
        unit: Unit code (``'m/s'``, ``'m'``, ``'rad'``) or None for dimensionless/text.
        mixed_external: For a mixed-sync asset (type D/E, Sec. 5.1.1): whether other assets,
            not the asset itself, keep this value current.
        description: One English sentence.
    """

    id_short: str
    xsd: str
    initial: str | float | int | bool
    unit: str | None = None
    mixed_external: bool = False
    description: str = ""


@dataclass(frozen=True)
class Arg:
    """One operation argument (an OperationVariable wrapping a Property)."""

    id_short: str
    xsd: str
    unit: str | None = None


@dataclass(frozen=True)
class OperationSpec:
    """One Operation of the ControlInterface submodel.

    Attributes:
        id_short: AAS idShort (also the OPC UA method name).
        inputs: Input variables in call order.
        outputs: Output variables in return order.
        description: One English sentence.
        external_sync: Present only for assets whose state others synchronise (Table 3.1
            sync 'external' or 'mixed').
    """

    id_short: str
    inputs: tuple[Arg, ...]
    outputs: tuple[Arg, ...]
    description: str = ""
    external_sync: bool = False


PHYSICAL_CLASSES = frozenset({"transfer_unit", "transport_module", "object"})
LOGICAL_CLASSES = frozenset(
    {"transport_module_system", "experiment_manager", "props", "knowledge_graph"}
)

_S, _D, _B, _I = "xs:string", "xs:double", "xs:boolean", "xs:int"

_BELTS = (
    PropertySpec("BeltSpeedLeft", _D, 0.0, "m/s", description="Speed of the left belt."),
    PropertySpec("BeltSpeedRight", _D, 0.0, "m/s", description="Speed of the right belt."),
    PropertySpec("BarrierNearInterrupted", _B, False, description="Near light barrier blocked."),
    PropertySpec("BarrierFarInterrupted", _B, False, description="Far light barrier blocked."),
    PropertySpec(
        "PossessedObjects",
        _S,
        "",
        mixed_external=True,
        description="Comma-separated ids of the objects on the belts.",
    ),
)


def _state() -> PropertySpec:
    return PropertySpec("State", _S, "idle", description="Current state.")


def _count(id_short: str, what: str) -> PropertySpec:
    return PropertySpec(id_short, _I, 0, description=f"Number of {what}.")


OPERATIONAL_DATA: Mapping[str, tuple[PropertySpec, ...]] = MappingProxyType(
    {
        "transfer_unit": (
            *_BELTS,
            PropertySpec(
                "DockedTransportModule",
                _S,
                "",
                mixed_external=True,
                description="Id of the docked transport module, '' if none.",
            ),
        ),
        "transport_module": (
            *_BELTS,
            PropertySpec("PoseX", _D, 0.0, "m", description="Map x of the robot."),
            PropertySpec("PoseY", _D, 0.0, "m", description="Map y of the robot."),
            PropertySpec("PoseTheta", _D, 0.0, "rad", description="Heading of the robot."),
            PropertySpec("DockedAt", _S, "", description="Station/unit docked at, '' if none."),
            PropertySpec(
                "State",
                _S,
                "idle",
                description="idle|navigating|docking|scanning|transferring (Fig. 5.9a).",
            ),
            PropertySpec("CurrentTask", _S, "", description="Id of the running task, '' if none."),
        ),
        "object": (
            PropertySpec("PossessedBy", _S, "", description="Id of the possessing asset."),
            PropertySpec(
                "Face", _S, "", description="Face it rested on in its latest transfer (Eq. 5.5)."
            ),
            PropertySpec(
                "Conveyor", _S, "", description="Conveyor of its latest transfer (Eq. 5.6)."
            ),
            PropertySpec(
                "Theta", _D, 0.0, "rad", description="Yaw of its latest transfer (Eq. 5.4)."
            ),
            PropertySpec(
                "LastTransfer",
                _S,
                "",
                description="Outcome of its last finished transfer (delivered, failed at "
                "pick-up, ...), '' before any.",
            ),
            PropertySpec(
                "TransferHistoryJson",
                _S,
                "[]",
                description="Its finished transfers, oldest first, as JSON (operation, "
                "source, target, module, outcome, face, conveyor, theta_deg, times).",
            ),
            PropertySpec(
                "PredictionsJson",
                _S,
                "{}",
                description="The calibrated twin's prediction of each pre-transfer state "
                "(success share of both legs, its 95 % interval), the best and the worst "
                "state and the calibration campaign they come from, as JSON; '{}' before "
                "any campaign.",
            ),
        ),
        "transport_module_system": (
            _state(),
            _count("QueuedOperations", "queued transport operations"),
            _count("CompletedOperations", "completed transport operations"),
            PropertySpec(
                "Policy",
                _S,
                "nearest-idle",
                description="Scheduling policy: nearest-idle|predictive.",
            ),
            PropertySpec(
                "OperationsPerHour",
                _D,
                0.0,
                "1/h",
                description="Delivered operations per hour since the first order.",
            ),
            PropertySpec(
                "SuccessShare", _D, 0.0, description="Delivered among finished operations."
            ),
            PropertySpec(
                "SuccessShareLow",
                _D,
                0.0,
                description="Clopper-Pearson 95 % lower bound of SuccessShare.",
            ),
            PropertySpec(
                "SuccessShareHigh",
                _D,
                1.0,
                description="Clopper-Pearson 95 % upper bound of SuccessShare.",
            ),
            PropertySpec(
                "MeanLeadTime",
                _D,
                0.0,
                "s",
                description="Mean time from order to end of finished operations.",
            ),
            PropertySpec(
                "KpisJson",
                _S,
                "{}",
                description="Every KPI as JSON (utilisation, failures by reason).",
            ),
        ),
        "experiment_manager": (
            _state(),
            _count("ExperimentsDone", "finished experiments"),
            PropertySpec(
                "StudyState",
                _S,
                "none",
                description="none|starting|running|stopping|stopped|finished|failed.",
            ),
            PropertySpec("StudyPlan", _S, "", description="Hash (12 digits) of the study's plan."),
            PropertySpec("StudyStore", _S, "", description="The study's SQLite result store."),
            _count("StudyDone", "experiments of the study in its store"),
            _count("StudyPlanned", "experiments the study plans"),
            PropertySpec("StudyProgress", _D, 0.0, description="StudyDone / StudyPlanned."),
            PropertySpec("StudyRate", _D, 0.0, "1/s", description="Experiments per second."),
            PropertySpec(
                "StudyEtaS", _D, -1.0, "s", description="Seconds left at that rate; -1 unknown."
            ),
            PropertySpec(
                "CampaignProgress",
                _S,
                "",
                description="The calibration campaign's state, stage and done/total of the "
                "stage, '' before any.",
            ),
        ),
        "props": (
            _state(),
            _count("FusedPoses", "fused poses"),
            PropertySpec(
                "FusedPosesJson",
                _S,
                "{}",
                description="Each subject's fused pose (x, y m, theta rad) and standard "
                "deviations (sd_x, sd_y, sd_theta) as JSON.",
            ),
            PropertySpec(
                "DockingErrorsJson",
                _S,
                "{}",
                description="Each module's last fused docking error (its pose in the unit's "
                "goal frame) with standard deviations and covariance, as JSON.",
            ),
        ),
        "knowledge_graph": (
            _state(),
            _count("Triples", "triples in the graph"),
            _count("Assets", "assets described"),
        ),
    }
)

_OK = (Arg("ok", _B),)
_SET_BELT = OperationSpec(
    "SetBeltSpeed",
    (Arg("belt", _S), Arg("speed", _D, "m/s")),
    _OK,
    "Set one belt ('left'|'right') to a speed.",
)
_SET_POSSESSED = OperationSpec(
    "SetPossessedObjects",
    (Arg("objects", _S),),
    _OK,
    "External state sync: the comma-separated ids of the objects on the belts.",
    external_sync=True,
)
_TRANSFER_ARGS = (Arg("source", _S), Arg("target", _S), Arg("object", _S))

CONTROL_INTERFACE: Mapping[str, tuple[OperationSpec, ...]] = MappingProxyType(
    {
        "transfer_unit": (_SET_BELT, _SET_POSSESSED),
        "transport_module": (
            _SET_BELT,
            _SET_POSSESSED,
            OperationSpec("Dock", (Arg("unit", _S),), _OK, "Dock to a transfer unit."),
            OperationSpec("Undock", (), _OK, "Undock from the current unit."),
            OperationSpec(
                "ReleaseObject",
                (Arg("object", _S),),
                _OK,
                "An operator took the object off the belts: the module no longer carries it.",
            ),
            OperationSpec(
                "AssignOperation",
                (Arg("operation_id", _S), *_TRANSFER_ARGS, Arg("plan_json", _S)),
                _OK,
                "Take a transport operation from the TMS, with the state to load the object "
                "in; progress and result are reported back to it (ReportProgress).",
            ),
            OperationSpec(
                "Bid",
                (Arg("order_json", _S),),
                (Arg("bid_json", _S),),
                "Expected seconds to carry an order's object to each candidate unit.",
            ),
        ),
        "object": (),
        "transport_module_system": (
            OperationSpec(
                "SubmitTransportOperation",
                _TRANSFER_ARGS,
                (Arg("operation_id", _S),),
                "Place a transport operation for allocation; refused with the reason if "
                "impossible.",
            ),
            OperationSpec(
                "OrderTo",
                (Arg("object", _S), Arg("destination", _S)),
                (Arg("operation_id", _S),),
                "Order an object to a unit or a destination group; its source is where the "
                "ledger says it is (after the object's earlier orders: they chain).",
            ),
            OperationSpec(
                "Orders",
                (),
                (Arg("orders_json", _S),),
                "The order queue: every order with its state (queued, assigned, driving, "
                "docking, transferring, done, failed) and reason.",
            ),
            OperationSpec(
                "Kpis",
                (),
                (Arg("kpis_json", _S),),
                "Operations per hour, success share with its interval, lead time, "
                "utilisation, failures by reason.",
            ),
            OperationSpec(
                "OperationStatus",
                (Arg("operation_id", _S),),
                (Arg("status_json", _S),),
                "State (queued|running|finished) and result of a transport operation.",
            ),
            OperationSpec(
                "ReportProgress",
                (Arg("operation_id", _S), Arg("event_json", _S)),
                _OK,
                "A transport module reports a step, a moved object or the result of an "
                "operation it was assigned (idempotent).",
            ),
            OperationSpec(
                "Ledger",
                (),
                (Arg("ledger_json", _S),),
                "Where every object is (or was last seen), and the operations.",
            ),
            OperationSpec(
                "Locate",
                (Arg("object", _S), Arg("holder", _S)),
                _OK,
                "An operator states where an object whose location is unknown lies.",
            ),
        ),
        "experiment_manager": (
            OperationSpec(
                "RunExperiment",
                (
                    Arg("unit", _S),
                    Arg("object", _S),
                    Arg("face", _S),
                    Arg("conveyor", _S),
                    Arg("theta_deg", _I, "deg"),
                    Arg("seed", _I),
                ),
                (Arg("result_json", _S),),
                "Plan and run one transfer experiment.",
            ),
            OperationSpec(
                "Predict",
                (Arg("object", _S), Arg("runs", _I), Arg("seed", _I)),
                (Arg("predictions_json", _S),),
                "The twin's success share per pre-transfer state of an object, best first, "
                "from virtual experiments (28 states, runs each); '' while they run (the "
                "first call starts them; call again).",
            ),
            OperationSpec(
                "StartStudy",
                (Arg("plan_json", _S), Arg("store", _S)),
                (Arg("status_json", _S),),
                "Start a study from a JSON plan into a result store ('' : the manager's "
                "default); an empty plan resumes the last study; the same plan resumes it.",
            ),
            OperationSpec(
                "StopStudy",
                (),
                (Arg("status_json", _S),),
                "Stop the running study after the experiments in flight (resumable).",
            ),
            OperationSpec(
                "StudyStatus",
                (),
                (Arg("status_json", _S),),
                "State, progress, rate, ETA and store of the last study.",
            ),
            OperationSpec(
                "StartCampaign",
                (Arg("request_json", _S),),
                (Arg("status_json", _S),),
                "Start a calibration campaign on the floor's physical units from a JSON "
                "request (K experiments, runs, seed, ...); '' or the same request resumes it.",
            ),
            OperationSpec(
                "StopCampaign",
                (),
                (Arg("status_json", _S),),
                "Stop the running campaign after the experiments in flight (resumable).",
            ),
            OperationSpec(
                "CampaignStatus",
                (),
                (Arg("status_json", _S),),
                "State, stage, progress, plant experiments and floor time of the last "
                "campaign, and its summary once finished.",
            ),
        ),
        "props": (
            OperationSpec(
                "ReportPose",
                (
                    Arg("source", _S),
                    Arg("subject", _S),
                    Arg("x_m", _D, "m"),
                    Arg("y_m", _D, "m"),
                    Arg("theta_rad", _D, "rad"),
                    Arg("sigma_xy", _D, "m"),
                    Arg("sigma_theta", _D, "rad"),
                ),
                _OK,
                "Report an observed pose of a subject (pose-graph edge).",
            ),
            OperationSpec(
                "ReportRelativePose",
                (
                    Arg("source", _S),
                    Arg("subject", _S),
                    Arg("relative_to", _S),
                    Arg("x_m", _D, "m"),
                    Arg("y_m", _D, "m"),
                    Arg("theta_rad", _D, "rad"),
                    Arg("sigma_xy", _D, "m"),
                    Arg("sigma_theta", _D, "rad"),
                ),
                _OK,
                "Report a subject's pose in another node's frame, e.g. a unit camera's "
                "ChArUco observation of a docked module.",
            ),
            OperationSpec(
                "DockingError",
                (Arg("module", _S), Arg("unit", _S)),
                (Arg("estimate_json", _S),),
                "The fused pose of a module in a unit's docking goal frame, with its "
                "standard deviations and covariance.",
            ),
            OperationSpec(
                "FusedPose",
                (Arg("subject", _S),),
                (Arg("pose_json", _S),),
                "The fused pose estimate of a subject.",
            ),
        ),
        "knowledge_graph": (
            OperationSpec(
                "Query",
                (Arg("sparql", _S),),
                (Arg("result_json", _S),),
                "Answer a SPARQL query.",
            ),
            OperationSpec(
                "Heartbeat",
                (Arg("heartbeat_json", _S),),
                (Arg("directory_json", _S),),
                "Renew an asset's lease: with its description and live state, or a renewal "
                "(id and instance) when they did not change (refused with BadNotFound when no "
                "lease of that start of its process is held); answers the directory's version, "
                "and the endpoints of the online assets when the sender holds another version.",
            ),
            OperationSpec(
                "Leave",
                (Arg("asset_id", _S),),
                _OK,
                "An asset announces that it leaves the network.",
            ),
            OperationSpec(
                "Status",
                (),
                (Arg("status_json", _S),),
                "Every known asset with its address, process, liveness and state.",
            ),
        ),
    }
)


@dataclass(frozen=True)
class CapabilitySpec:
    """How an asset class realises one capability (the IDTA capability pattern).

    Attributes:
        realized_by: The elements that realise it, as ``(submodel, idShort)``: the
            ControlInterface operations that offer it, or the OperationalData properties
            that show it (a sensing capability has no operation).
        constraints: What it is bound to, as constant properties (value = the bound).
    """

    realized_by: tuple[tuple[str, str], ...]
    constraints: tuple[PropertySpec, ...] = ()


def _ops(*names: str) -> tuple[tuple[str, str], ...]:
    return tuple(("ControlInterface", n) for n in names)


def _shown_by(*names: str) -> tuple[tuple[str, str], ...]:
    return tuple(("OperationalData", n) for n in names)


# The objects and states the belts are made for: a belt's width (sim LayoutConfig), the
# starter cores' mass range (objects: the cores' generator clamps it to 2.2-4.9 kg), and the
# pre-transfer states (Eq. 5.5, 5.6, 6.4) an object may be loaded in.
_BELT_WIDTH = PropertySpec("BeltWidth", _D, 0.195, "m", description="Width of one belt.")
_MASS = (
    PropertySpec("ObjectMassMin", _D, 2.2, "kg", description="Lightest object it carries."),
    PropertySpec("ObjectMassMax", _D, 4.9, "kg", description="Heaviest object it carries."),
)
_STATES = (
    PropertySpec(
        "AcceptedFaces", _S, "front,back", description="Faces an object may rest on (Eq. 5.5)."
    ),
    PropertySpec(
        "AcceptedConveyors",
        _S,
        "left,both,right",
        description="Conveyors an object may lie on (Eq. 5.6).",
    ),
    PropertySpec("ThetaMin", _I, -179, "deg", description="Least yaw accepted (Eq. 6.4)."),
    PropertySpec("ThetaMax", _I, 180, "deg", description="Greatest yaw accepted (Eq. 6.4)."),
)
_SENSE = CapabilitySpec(_shown_by("BarrierNearInterrupted", "BarrierFarInterrupted"))

CAPABILITY_SPECS: Mapping[str, Mapping[str, CapabilitySpec]] = MappingProxyType(
    {
        "transfer_unit": MappingProxyType(
            {
                "transfer": CapabilitySpec(
                    _ops("SetBeltSpeed"),
                    (
                        _BELT_WIDTH,
                        PropertySpec(
                            "BeltLength", _D, 0.5, "m", description="Length of the belts."
                        ),
                        *_MASS,
                        *_STATES,
                    ),
                ),
                "sense": _SENSE,
            }
        ),
        "transport_module": MappingProxyType(
            {
                "transport": CapabilitySpec(_ops("AssignOperation", "Bid"), (*_MASS, *_STATES)),
                "transfer": CapabilitySpec(
                    _ops("Dock", "Undock", "SetBeltSpeed"),
                    (
                        _BELT_WIDTH,
                        PropertySpec(
                            "BeltLength", _D, 0.65, "m", description="Length of the belts."
                        ),
                        *_MASS,
                        *_STATES,
                    ),
                ),
                "sense": _SENSE,
            }
        ),
        "transport_module_system": MappingProxyType(
            {"allocate": CapabilitySpec(_ops("SubmitTransportOperation", "OrderTo"))}
        ),
        "experiment_manager": MappingProxyType(
            {
                "experiment": CapabilitySpec(
                    _ops("RunExperiment", "Predict", "StartStudy", "StartCampaign"),
                    (
                        PropertySpec(
                            "PredictRunsMax",
                            _I,
                            100,
                            description="Most runs per state a prediction may ask for.",
                        ),
                    ),
                )
            }
        ),
        "props": MappingProxyType(
            {
                "fuse_poses": CapabilitySpec(
                    _ops("ReportPose", "ReportRelativePose", "FusedPose", "DockingError")
                )
            }
        ),
        "knowledge_graph": MappingProxyType(
            {
                "knowledge": CapabilitySpec(
                    _ops("Query"),
                    (
                        PropertySpec(
                            "QueryLanguage",
                            _S,
                            "SPARQL 1.1 SELECT",
                            description="The queries it answers (read only).",
                        ),
                    ),
                )
            }
        ),
        "object": MappingProxyType({}),
    }
)


def capability_specs(desc: AssetDescriptor) -> dict[Capability, CapabilitySpec]:
    """How the asset realises each capability it offers: its generic class's row of
    `CAPABILITY_SPECS` (`AssetDescriptor.role_class`) with the asset's own constraint values
    (`AssetDescriptor.constraints`) in place of the class's. A capability its class does not
    say how to realise is left out.

    Raises:
        InputError: A constraint the asset sets that its class's capability does not have
            (only known constraints: the ontology defines each), or a value of another type.
    """
    rows = CAPABILITY_SPECS.get(desc.role_class, {})
    own: dict[Capability, dict[str, float | str]] = {}
    for cap, name, value in desc.constraints:
        spec = rows.get(cap.value) if cap in desc.capabilities else None
        known = {c.id_short: c for c in spec.constraints} if spec else {}
        if name not in known:
            raise InputError(
                f"{desc.asset_id}: capability {cap.value} has no constraint {name!r}; "
                f"known: {', '.join(known) or 'none'}"
            )
        if isinstance(value, str) != isinstance(known[name].initial, str):
            raise InputError(f"{desc.asset_id}: constraint {name} must be like "
                             f"{known[name].initial!r}, got {value!r}")  # fmt: skip
        own.setdefault(cap, {})[name] = value
    out = {}
    for cap in desc.capabilities:
        spec = rows.get(cap.value)
        if spec is None:
            continue
        values = own.get(cap, {})
        bound = tuple(
            replace(c, initial=values.get(c.id_short, c.initial)) for c in spec.constraints
        )
        out[cap] = replace(spec, constraints=bound)
    return out
