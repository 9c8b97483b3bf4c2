"""Tracker (Sec. 5.4.3): identities through missed frames, Kalman filter with belt input."""

from __future__ import annotations

import pytest

from transfertwin.perception import AABB, Tracker, TrackerConfig

DT = 1.0 / 15.0
V = 0.15  # belt speed, m/s: 1 cm per frame


def _box(x: float, y: float = 0.0) -> AABB:
    return AABB((x, y, 0.05), (0.1, 0.05, 0.05), 500)


def _run(tracker: Tracker, velocity, missed: range, frames: int = 20) -> list[int]:
    ids = []
    for k in range(frames):
        boxes = [] if k in missed else [_box(-0.4 + V * DT * k)]
        tracks = tracker.step(boxes, DT, velocity)
        ids.append(tracks[0].track_id if len(tracks) == 1 else -len(tracks))
    return ids


def test_identity_survives_five_missed_frames_with_the_belt_as_control_input() -> None:
    ids = _run(Tracker(), (V, 0.0), missed=range(5, 10))
    assert ids == [1] * 20


def test_without_the_belt_input_the_same_gap_loses_the_identity() -> None:
    """The object moves 6 cm during the gap, beyond the 4 cm gate: only the control input
    keeps the track (so the test above can fail)."""
    ids = _run(Tracker(), (0.0, 0.0), missed=range(5, 10))
    assert ids[-1] != 1


def test_prediction_during_missed_frames_follows_the_belt() -> None:
    tracker = Tracker()
    tracker.step([_box(-0.4)], DT, (V, 0.0))
    for _ in range(5):
        (track,) = tracker.step([], DT, (V, 0.0))
    assert track.mean[0] == pytest.approx(-0.4 + 5 * V * DT, abs=1e-12)
    assert track.missed == 5


def test_two_objects_keep_their_ids_and_a_lost_track_is_dropped() -> None:
    tracker = Tracker(TrackerConfig(max_missed=3))
    tracker.step([_box(-0.4, 0.1), _box(-0.4, -0.1)], DT)
    tracks = tracker.step([_box(-0.4, -0.1), _box(-0.4, 0.1)], DT)  # order swapped
    by_id = {t.track_id: t.mean[1] for t in tracks}
    assert by_id[1] > 0 > by_id[2]
    for _ in range(4):
        tracks = tracker.step([_box(-0.4, -0.1)], DT)
    assert [t.track_id for t in tracks] == [2]


def test_new_detection_far_away_opens_a_new_track() -> None:
    tracker = Tracker()
    tracker.step([_box(-0.4)], DT)
    tracks = tracker.step([_box(-0.1)], DT)
    assert sorted(t.track_id for t in tracks) == [1, 2]
