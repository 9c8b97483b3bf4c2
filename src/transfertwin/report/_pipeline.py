"""One call from a results table to tables, figures and the HTML report."""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from transfertwin.report._html import write_report
from transfertwin.report._partial import StudyProgress
from transfertwin.study.fullstate import AnalysisResult, ResultRecord, analyze

__all__ = ["analyze_and_report"]


def analyze_and_report(
    rows: Iterable[Mapping[str, object] | ResultRecord],
    out_dir: str | os.PathLike[str],
    params: Mapping[str, object] | None = None,
    *,
    window: int = 21,
    progress: StudyProgress | None = None,
) -> tuple[AnalysisResult, Path]:
    """`transfertwin.study.analyze` followed by `write_report`.

    Writes ``states.csv``, ``selection.json``, ``figures/*.png`` and
    ``report.html`` into ``out_dir``. Bad input raises before any file is written.

    Args:
        rows: Results-table rows (see `transfertwin.study.analyze`).
        out_dir: Output folder, created if needed.
        params: Study parameters listed in the report.
        window: Moving-average window of Eq. 6.27, degrees.
        progress: Done/planned of the study; a partial study's report says so.

    Returns:
        The analysis and the path of ``report.html``.

    Raises:
        InputError: On bad rows or window.
    """
    analysis = analyze(rows, out_dir, window=window)
    return analysis, write_report(out_dir, analysis, dict(params or {}), progress=progress)
