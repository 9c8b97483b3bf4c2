"""A partial study says so (issue 30.5): done/planned in a banner and what it means."""

from __future__ import annotations

from pathlib import Path

import pytest

from transfertwin._errors import InputError
from transfertwin.report import StudyProgress, partial_banner_html, partial_line, write_report
from transfertwin.study.fullstate import analyze


def test_partial_study_banner_says_done_of_planned_and_what_it_means() -> None:
    progress = StudyProgress(done=24, planned=60, states_done=3, states_planned=15)
    assert progress.partial
    banner = partial_banner_html(progress)
    assert "Partial study" in banner and "24 of 60 planned experiments" in banner
    assert "3 of 15 planned states" in banner
    assert "chosen among the states run so far" in banner and "wider" in banner
    line = partial_line(progress)
    assert line.startswith("partial study: 24 of 60 planned experiments done (40%)")
    assert "\n" not in line


@pytest.mark.parametrize(
    "progress",
    [
        StudyProgress(done=60, planned=60, states_done=15, states_planned=15),
        StudyProgress(done=24, planned=60, states_done=3, states_planned=15, adaptive=True),
    ],
)
def test_a_finished_or_adaptive_study_has_no_banner(progress: StudyProgress) -> None:
    assert not progress.partial
    assert partial_banner_html(progress) == "" and partial_line(progress) == ""


@pytest.mark.parametrize(
    ("done", "planned", "states_done", "states_planned", "needle"),
    [
        (61, 60, 3, 15, "61 results but its plan has 60"),
        (-1, 60, 3, 15, ">= 0"),
        (24, 60, 16, 15, "16 states but its plan has 15"),
    ],
)
def test_impossible_progress_is_bad_input(done, planned, states_done, states_planned, needle):
    with pytest.raises(InputError, match=needle):
        StudyProgress(done, planned, states_done, states_planned)


def test_report_of_a_partial_study_opens_with_the_banner(tmp_path: Path) -> None:
    rows = [
        dict(object_id="o1", face="front", conveyor="both", theta_deg=t, success=int(t > 0))
        for t in (-60, 60)
    ]
    progress = StudyProgress(done=2, planned=32, states_done=2, states_planned=16)
    text = write_report(tmp_path, analyze(rows), {}, progress=progress).read_text("utf-8")
    assert text.index("Partial study") < text.index("id='summary'")
    full = StudyProgress(done=32, planned=32, states_done=16, states_planned=16)
    text = write_report(tmp_path, analyze(rows), {}, progress=full).read_text("utf-8")
    assert "Partial study" not in text
