"""The strip image: orientation of the view, annotations, rows per phase."""

from __future__ import annotations

import numpy as np
from PIL import Image

from transfertwin.sim import SceneConfig, group_frames, render_strip, strip_pixels
from transfertwin.study.experiment import ExperimentSpec, run_experiment, system_for


def test_group_frames_keeps_each_phase_first_and_last() -> None:
    labels = ["there"] * 10 + ["back"] * 3
    assert group_frames(labels, 4) == [[0, 3, 6, 9], [10, 11, 12]]
    assert group_frames([], 4) == []


def test_view_shows_travel_left_to_right_and_the_left_belt_on_the_left(box_stl) -> None:
    """Looking in the direction of travel (+x), the left belt (y > 0) is on the left: in
    the strip, +x runs to the right and the left belt is the far one, at the top."""
    system = system_for(str(box_stl), "mm", SceneConfig())
    (u_tm, v_left), (u_tu, v_right) = strip_pixels(
        system, np.array([[-0.3, 0.1, 0.0], [0.3, -0.1, 0.0]])
    )
    assert u_tm < u_tu  # TM left of TU: travel TM → TU is left to right
    assert v_left < v_right  # left belt above the right belt
    ends = strip_pixels(system, np.array([[-0.65, 0.2, 0.0], [0.52, -0.2, 0.0]]))
    assert (ends[:, 0] > 0).all() and (ends[:, 0] < 480).all()  # both units in view


def test_strip_has_a_row_per_phase_and_marks_barriers(box_stl, tmp_path) -> None:
    spec = ExperimentSpec(str(box_stl), "front", "left", 0, units="mm", record=True)
    result = run_experiment(spec)
    assert result.success == 1
    system = system_for(spec.object_ref, spec.units, spec.scene)
    poses = [(f.phase, f.t_s, f.qpos) for f in result.frames]
    out = render_strip(
        system, poses, tmp_path / "s.png", title=["a", "b"], travel={"there": 1, "back": -1}
    )
    with Image.open(out) as img:
        rgb = np.asarray(img.convert("RGB"))
    assert rgb.shape[1] == 4 * 480  # four frames per row
    assert rgb.shape[0] > 2 * 260  # two rows (there, back) plus header and legend
    # The object crosses the TU's near barrier: some frame shows an interrupted (yellow) beam.
    yellow = (rgb[..., 0] > 230) & (rgb[..., 1] > 180) & (rgb[..., 1] < 215) & (rgb[..., 2] < 30)
    assert yellow.sum() > 200
    # The object is drawn on the left (far, upper) belt in the first frame.
    header = 10 + 24 * 2
    first = rgb[header : header + 260, :480].astype(int)
    tan = (abs(first[..., 0] - 158) < 40) & (abs(first[..., 1] - 133) < 40) & (first[..., 2] < 120)
    rows = np.nonzero(tan.any(axis=1))[0]
    belts_mid = strip_pixels(system, np.array([[-0.325, 0.0, 0.0]]))[0, 1]
    assert rows.size and rows.mean() < belts_mid
