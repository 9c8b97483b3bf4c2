"""Plot data, matplotlib renderers and the HTML report (Fig. 6.6/6.7, 6.20–6.23).

Each plot has a pure data function returning a frozen dataclass and a renderer
that draws it into a pyplot-free `matplotlib.figure.Figure`; nothing here calls
``plt.show()``. This layer may import `transfertwin.study` and `transfertwin.ots`.
"""

from transfertwin.report._binary_polar import (
    LABEL_MAX_STATES,
    RING_RADIUS,
    BinaryPoint,
    BinaryPolar,
    BinaryState,
    binary_polar_data,
    plot_binary_polar,
)
from transfertwin.report._calibration_plots import (
    ScoreDistribution,
    plot_score_distribution,
    score_distribution_data,
)
from transfertwin.report._docking_plots import (
    DockingCorrelations,
    DockingHistograms,
    docking_correlation_data,
    docking_hist_data,
    plot_correlation_matrices,
    plot_docking_histograms,
)
from transfertwin.report._fidelity_plots import (
    Curve,
    FidelityPlot,
    ShareBar,
    fidelity_plot_data,
    plot_fidelity,
)
from transfertwin.report._figure import figure_png, yaw_tick_labels
from transfertwin.report._html import REPORT_NAME, format_value, write_report
from transfertwin.report._interval_plot import IntervalPlot, interval_plot_data, plot_intervals
from transfertwin.report._navigation_plots import plot_docking_run
from transfertwin.report._partial import StudyProgress, partial_banner_html, partial_line
from transfertwin.report._pipeline import analyze_and_report
from transfertwin.report._polar_full_state import (
    PANEL_CONVEYORS,
    SMOOTH_GRID_DEG,
    SMOOTH_MIN_N,
    PolarFullState,
    PolarMarker,
    PolarPanel,
    circular_smooth,
    plot_polar_full_state,
    polar_full_state_data,
)
from transfertwin.report._rehearsal_html import (
    REHEARSAL_FIGURE,
    REHEARSAL_REPORT_NAME,
    plot_rehearsal_curve,
    write_rehearsal_curve_report,
    write_rehearsal_report,
)
from transfertwin.report._rehearsal_plots import (
    F05Point,
    RehearsalPlot,
    ValidatedState,
    f05_change_text,
    plot_rehearsal,
    rehearsal_plot_data,
)
from transfertwin.report._sensitivity_plots import (
    MorrisBar,
    SensitivityPanel,
    morris_plot_data,
    plot_morris,
    plot_sensitivity,
    sensitivity_plot_data,
)
from transfertwin.report._validation_plots import (
    ValidationPlot,
    plot_validation,
    validate_and_report,
    validation_plot_data,
)

__all__ = [
    "LABEL_MAX_STATES",
    "PANEL_CONVEYORS",
    "REHEARSAL_FIGURE",
    "REHEARSAL_REPORT_NAME",
    "REPORT_NAME",
    "RING_RADIUS",
    "SMOOTH_GRID_DEG",
    "SMOOTH_MIN_N",
    "BinaryPoint",
    "BinaryPolar",
    "BinaryState",
    "Curve",
    "DockingCorrelations",
    "DockingHistograms",
    "F05Point",
    "FidelityPlot",
    "IntervalPlot",
    "MorrisBar",
    "PolarFullState",
    "PolarMarker",
    "PolarPanel",
    "RehearsalPlot",
    "ScoreDistribution",
    "SensitivityPanel",
    "ShareBar",
    "StudyProgress",
    "ValidatedState",
    "ValidationPlot",
    "analyze_and_report",
    "binary_polar_data",
    "circular_smooth",
    "docking_correlation_data",
    "docking_hist_data",
    "f05_change_text",
    "fidelity_plot_data",
    "figure_png",
    "format_value",
    "interval_plot_data",
    "morris_plot_data",
    "partial_banner_html",
    "partial_line",
    "plot_binary_polar",
    "plot_correlation_matrices",
    "plot_docking_histograms",
    "plot_docking_run",
    "plot_fidelity",
    "plot_intervals",
    "plot_morris",
    "plot_polar_full_state",
    "plot_rehearsal",
    "plot_rehearsal_curve",
    "plot_score_distribution",
    "plot_sensitivity",
    "plot_validation",
    "polar_full_state_data",
    "rehearsal_plot_data",
    "score_distribution_data",
    "sensitivity_plot_data",
    "validate_and_report",
    "validation_plot_data",
    "write_rehearsal_curve_report",
    "write_rehearsal_report",
    "write_report",
    "yaw_tick_labels",
]
