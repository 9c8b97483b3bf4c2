"""The virtual experiment E^V, study plans, profiles and the resumable runner (Sec. 6.2, 6.6)."""

from typing import TYPE_CHECKING

from transfertwin._lazy import lazy_exports

if TYPE_CHECKING:
    from transfertwin.study.experiment._demo import real_docking_error, run_demo
    from transfertwin.study.experiment._experiment import (
        LEGS,
        RESULT_COLUMNS,
        SENSORS,
        ExperimentResult,
        ExperimentSpec,
        Frame,
        run_experiment,
        scene_controller,
        system_for,
    )
    from transfertwin.study.experiment._plan import (
        PRESETS,
        SAMPLING_MODES,
        Preset,
        StudyPlan,
        check_theta_step,
        delivery_docking_seed,
        experiment_seeds,
        parse_objects,
        plan_parameters,
    )
    from transfertwin.study.experiment._pool import WarmPool
    from transfertwin.study.experiment._profile import (
        load_profile,
        profile_toml,
        save_profile,
        scene_from_dict,
        scene_to_dict,
    )
    from transfertwin.study.experiment._ray import RayExecutor
    from transfertwin.study.experiment._runner import (
        Executor,
        ObjectSummary,
        StudyOutcome,
        check_plan,
        run_rows,
        run_study,
        run_tagged,
        summarize,
    )
    from transfertwin.study.experiment._warp import WarpExecutor, warp_available

__all__ = [
    "LEGS",
    "PRESETS",
    "RESULT_COLUMNS",
    "SAMPLING_MODES",
    "SENSORS",
    "Executor",
    "ExperimentResult",
    "ExperimentSpec",
    "Frame",
    "ObjectSummary",
    "Preset",
    "RayExecutor",
    "StudyOutcome",
    "StudyPlan",
    "WarmPool",
    "WarpExecutor",
    "check_plan",
    "check_theta_step",
    "delivery_docking_seed",
    "experiment_seeds",
    "load_profile",
    "parse_objects",
    "plan_parameters",
    "profile_toml",
    "real_docking_error",
    "run_demo",
    "run_experiment",
    "run_rows",
    "run_study",
    "run_tagged",
    "save_profile",
    "scene_controller",
    "scene_from_dict",
    "scene_to_dict",
    "summarize",
    "system_for",
    "warp_available",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
