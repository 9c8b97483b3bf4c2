"""The docking-error generator: marginals and a Gaussian copula on scipy (Sec. 6.4)."""

from transfertwin.study.docking._copula import (
    COPULA_KINDS,
    MIN_ROWS,
    GaussianCopula,
    PerStationCopula,
    copula_from_dict,
    normal_scores,
)
from transfertwin.study.docking._io import (
    DOCKING_MODEL_KINDS,
    STATION_COLUMN,
    docking_model,
    load_docking_model,
    read_docking_errors,
)
from transfertwin.study.docking._marginals import (
    CRITERION,
    FAMILIES,
    KS_ALPHA,
    RANGE_MARGIN,
    CandidateFit,
    Marginal,
    MarginalFamily,
    MarginalFit,
    fit_marginal,
    marginal_family,
)
from transfertwin.study.docking._models import (
    DockingErrorModel,
    FixedDockingError,
    ResampledDockingErrors,
    docking_model_from_dict,
    measured_docking_errors,
)

__all__ = [
    "COPULA_KINDS",
    "CRITERION",
    "DOCKING_MODEL_KINDS",
    "FAMILIES",
    "KS_ALPHA",
    "MIN_ROWS",
    "RANGE_MARGIN",
    "STATION_COLUMN",
    "CandidateFit",
    "DockingErrorModel",
    "FixedDockingError",
    "GaussianCopula",
    "Marginal",
    "MarginalFamily",
    "MarginalFit",
    "PerStationCopula",
    "ResampledDockingErrors",
    "copula_from_dict",
    "docking_model",
    "docking_model_from_dict",
    "fit_marginal",
    "load_docking_model",
    "marginal_family",
    "measured_docking_errors",
    "normal_scores",
    "read_docking_errors",
]
