"""The page and the words of one rehearsal (issue 30, item 7).

DOC is the ``rehearsal.json`` of ``rehearse --plant-seed 1 --objects o3,o7
--calibration-experiments 40`` (the README's example), rounded: F0.5 before 0.897, after
0.806 on 12 held-out rows, after − before 95 % CI [-0.30, 0.07]. Expected values are
read off that document or hand-derived; Clopper–Pearson 95 % for 6/10 is [0.2624,
0.8784] and for 10/10 [0.6915, 1] (published tables).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from matplotlib.figure import Figure

from transfertwin._errors import InputError
from transfertwin.cli._rehearse import _summary_line
from transfertwin.report import (
    REHEARSAL_FIGURE,
    f05_change_text,
    plot_rehearsal,
    rehearsal_plot_data,
    write_rehearsal_report,
)

DOC = json.loads(
    '{"f05_before":0.8974,"f05_before_ci":[0.7166,1.0],"f05_after_ci":[0.5806,0.9546],"f05_ba'
    'se_rate_ci":[0.3846,0.8621],"f05_delta_ci":[-0.2951,0.067],"counter_measures":["mass","s'
    'tability","compliance"],"f05_after":0.8065,"significant_best":0,"significant_worst":1,"s'
    'ignificant_best_objects":[],"significant_worst_objects":["o7"],"scores_after":{"f05":0.8'
    '065,"precision":0.8333,"recall":0.7143,"accuracy":0.75,"brier":0.1667},"objects":{"o3":{'
    '"calibration":{"calibrated":true,"proxy":"objects/o3.proxy.json","depth_mm":{"back":16.0'
    ',"front":8.0},"measured_mass_kg":3.022,"measured_com_mm":[-4.1,0.6,3.0]},"best":{"face":'
    '"front","conveyor":"both","theta_deg":-90,"n_v":10,"k_v":6,"p_v":0.6,"n_p":10,"k_p":4,"p'
    '_p":0.4,"diff_low":-0.2063,"diff_high":0.5278,"significant":false},"worst":{"face":"fron'
    't","conveyor":"left","theta_deg":0,"n_v":10,"k_v":0,"p_v":0.0,"n_p":10,"k_p":1,"p_p":0.1'
    ',"diff_low":-0.4042,"diff_high":0.1894,"significant":false},"plant_calibration_share":0.'
    '2},"o7":{"calibration":{"calibrated":true,"proxy":"objects/o7.proxy.json","depth_mm":{"b'
    'ack":24.0,"front":0.0},"measured_mass_kg":4.229,"measured_com_mm":[-1.7,1.5,0.3]},"best"'
    ':{"face":"front","conveyor":"both","theta_deg":-90,"n_v":10,"k_v":10,"p_v":1.0,"n_p":10,'
    '"k_p":10,"p_p":1.0,"diff_low":-0.2775,"diff_high":0.2775,"significant":false},"worst":{"'
    'face":"back","conveyor":"both","theta_deg":90,"n_v":10,"k_v":5,"p_v":0.5,"n_p":10,"k_p":'
    '10,"p_p":1.0,"diff_low":-0.7634,"diff_high":-0.1174,"significant":true},"plant_calibrati'
    'on_share":0.8}},"tuned_scene":null,"virtual_unstable":0,"virtual_rerun":0,"plant_experim'
    'ents":80,"virtual_experiments":416,"scores_before":{"f05":0.8974,"precision":0.875,"reca'
    'll":1.0,"accuracy":0.9167,"brier":0.0417},"f05_base_rate":0.6364,"held_out":12,"training'
    '":28,"ablations":{},"operations":null,"config":{"plant_seed":1,"objects":["o3","o7"],"ca'
    'libration_experiments":40,"runs":2,"validation_runs":10,"theta_step":90,"holdout":0.3,"t'
    'est_experiments":0,"depths_mm":[8.0,16.0,24.0,32.0],"tune_trials":0,"seed":0,"workers":2'
    ',"ablate":[],"operations":0},"seconds":117.0}'
)


def test_plot_data_holds_f05_with_intervals_and_the_validated_states() -> None:
    data = rehearsal_plot_data(DOC)
    assert [p.label for p in data.f05] == [
        "always 'success'",
        "twin before calibration",
        "twin after calibration",
    ]
    assert data.f05[2].f05 == pytest.approx(0.8065) and data.f05[2].ci == (0.5806, 0.9546)
    assert data.held_out == 12 and data.delta_ci == (-0.2951, 0.067)
    assert [(s.object_id, s.kind) for s in data.states] == [
        ("o3", "best"),
        ("o3", "worst"),
        ("o7", "best"),
        ("o7", "worst"),
    ]
    o3_best, o7_best = data.states[0], data.states[2]
    assert o3_best.state == "front both -90°" and (o3_best.k_v, o3_best.n_v) == (6, 10)
    assert o3_best.ci_v == pytest.approx((0.2624, 0.8784), abs=1e-4)
    assert o7_best.ci_p == pytest.approx((0.6915, 1.0), abs=1e-4)
    assert [s.significant for s in data.states] == [False, False, False, True]


def test_plot_data_needs_the_f05_figures() -> None:
    with pytest.raises(InputError, match="f05_after"):
        rehearsal_plot_data({"f05_before": 0.5, "f05_base_rate": 0.6})


def test_a_change_on_12_rows_is_called_not_significant() -> None:
    text = f05_change_text(rehearsal_plot_data(DOC))
    assert text.startswith("after − before -0.091, 95 % CI [-0.30, 0.07]: not significant")
    assert "12 held-out rows are few" in text


def test_a_change_whose_interval_excludes_zero_on_many_rows_is_significant() -> None:
    doc = {**DOC, "held_out": 200, "f05_delta_ci": [0.05, 0.2]}
    assert f05_change_text(rehearsal_plot_data(doc)).endswith("[0.05, 0.20]: significant")


def test_the_renderer_draws_f05_and_the_validation() -> None:
    fig = plot_rehearsal(rehearsal_plot_data(DOC))
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    no_states = plot_rehearsal(rehearsal_plot_data({**DOC, "objects": {}}))
    assert len(no_states.axes) == 1


def test_the_page_explains_plots_and_folds_the_configuration(tmp_path: Path) -> None:
    page = write_rehearsal_report(DOC, tmp_path).read_text(encoding="utf-8")
    assert (tmp_path / REHEARSAL_FIGURE).read_bytes()[:4] == b"\x89PNG"
    body = re.sub(r"<details>.*?</details>", "", page, flags=re.S)
    assert "f05_" not in body and "_ci" not in body  # JSON names only in the folded glossary
    assert "{" not in page.split("</style>")[1]  # no Python dicts
    assert "<pre>" not in page  # no raw configuration line
    assert "<details><summary>Configuration</summary>" in page
    assert page.index("What it found") < page.index("data:image/png;base64,")
    assert "not significant (the interval holds 0)" in page
    assert "back 16 mm, front 8 mm" in page
    assert "have too few runs to see a difference" in page  # 10 runs per best/worst state


def test_the_cli_line_says_the_small_n_caveat_and_names_the_report(tmp_path: Path) -> None:
    line = _summary_line(DOC, 2, tmp_path)
    assert "on 12 held-out rows before 0.897, after 0.806" in line
    assert "not significant (the interval holds 0)" in line
    assert line.splitlines()[-1].strip().startswith(f"report: {tmp_path / 'report.html'}")


def test_both_scores_are_explained_and_brier_stands_beside_f05(tmp_path: Path) -> None:
    page = write_rehearsal_report(DOC, tmp_path).read_text(encoding="utf-8")
    assert "<b>F0.5</b> scores the twin's yes/no predictions" in page
    assert "<b>Brier score</b> scores the twin's probabilities" in page
    found = page[page.index("What it found") :]
    assert "after 0.806 [0.58, 0.95]" in found
    assert "Brier score: before 0.042, after 0.167 (lower is better)" in found


def test_a_calibration_that_made_things_worse_gets_a_plain_verdict(tmp_path: Path) -> None:
    page = write_rehearsal_report(DOC, tmp_path).read_text(encoding="utf-8")
    assert (
        "Calibration made the twin worse on these rows</b>: F0.5 fell from 0.897 to 0.806 "
        "and the Brier score rose from 0.042 to 0.167"
    ) in page
    # 28 training rows over 2 objects x 2 faces: about 7 outcomes per face's depth.
    assert (
        "With 40 calibration experiments (28 to calibrate, 12 held out to score) for 2 "
        "objects: each face's protrusion depth was chosen on about 7 yes/no outcomes"
    ) in page
    assert "about 7 yes/no outcomes" in page
    better = {**DOC, "f05_after": 0.95, "scores_after": {**DOC["scores_after"], "brier": 0.03}}
    page = write_rehearsal_report(better, tmp_path / "b").read_text(encoding="utf-8")
    assert "made the twin worse" not in page


def test_the_thresholded_block_is_shown(tmp_path: Path) -> None:
    block = {
        "threshold_before": 0.5, "threshold_after": 0.75,
        "threshold_source": "chosen on the 28 training rows (best F0.5 there)",
        "f05_before": 0.9, "f05_before_ci": [0.7, 1.0], "brier_before": 0.0417,
        "brier_before_ci": [0.0, 0.125], "f05_after": 0.8, "f05_after_ci": [0.55, 0.95],
        "brier_after": 0.1667, "brier_after_ci": [0.04, 0.33], "f05_delta": -0.1,
        "f05_delta_ci": [-0.3, 0.05], "brier_delta": 0.125, "brier_delta_ci": [0.0, 0.29],
    }  # fmt: skip
    page = write_rehearsal_report({**DOC, "thresholded": block}, tmp_path).read_text("utf-8")
    assert "<h2>Decisions at a threshold</h2>" in page
    assert "chosen on the 28 training rows (best F0.5 there)" in page
    assert "<td>twin after calibration</td><td>0.75</td><td>0.800 [0.55, 0.95]</td>" in page
    assert "<td>0.167 [0.04, 0.33]</td>" in page
    assert "<td>after − before</td><td></td><td>-0.100 [-0.30, 0.05]</td>" in page
    assert "+0.125 [0.00, 0.29]" in page


def test_the_counter_measures_are_explained(tmp_path: Path) -> None:
    page = write_rehearsal_report(DOC, tmp_path).read_text(encoding="utf-8")
    assert "<b>mass</b>: each core is weighed and balanced" in page
    assert "<b>stability</b>: a run with an implausible event" in page
    assert "<b>compliance</b>: the proxy's features yield" in page


def test_the_hidden_truth_stands_beside_the_fitted_proxy(tmp_path: Path) -> None:
    """Plant seed 1 (plant.secret beside the record) hides o3 front 17.0 mm, back 12.6 mm,
    o7 front plain, back 10.1 mm, μ 0.4385, gap 15.86 mm; calibration fitted o3 front 8,
    back 16, o7 front 0, back 24 mm from the candidates 0, 8, 16, 24, 32."""
    from transfertwin.plant import PLANT_SEED_FILE, write_plant_seed

    write_plant_seed(tmp_path / PLANT_SEED_FILE, 1)
    page = write_rehearsal_report(DOC, tmp_path).read_text(encoding="utf-8")
    truth = page[page.index("<h2>Hidden truth and fitted proxy</h2>") :]
    rows = dict(
        ((m[0], m[1]), m[2:])
        for m in re.findall(
            r"<tr><td>(o\d)</td><td>(front|back)</td><td>([\d.]+) mm[^<]*</td>"
            r"<td>([\d.]+) mm</td><td>(.*?)</td></tr>",
            truth,
        )
    )
    assert rows[("o3", "front")][:2] == ("17.0", "8")
    assert "missed by 9 mm" in rows[("o3", "front")][2]
    assert "the candidate 16 mm was closer" in rows[("o3", "front")][2]
    assert "recovered" in rows[("o3", "back")][2]  # 16 against 12.6: within 4 mm
    assert "recovered" in rows[("o7", "front")][2] and rows[("o7", "front")][0] == "0.0"
    assert "missed by 14 mm" in rows[("o7", "back")][2]
    assert "<td>friction μ</td><td>0.439</td><td>not tuned" in truth
    assert "<td>gap</td><td>15.9 mm</td><td>not tuned (the default scene has 11.9 mm)" in truth
    assert "<td>3.012 kg</td><td>3.022 kg</td>" in truth  # o3: true mass beside the scale's


def test_without_the_plant_seed_the_page_says_the_truth_is_unknown(tmp_path: Path) -> None:
    page = write_rehearsal_report(DOC, tmp_path).read_text(encoding="utf-8")
    assert "is not beside this record, so its hidden truth cannot be shown" in page
