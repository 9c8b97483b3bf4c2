"""`merge_hulls`: a hull budget per object (least added volume first, features kept)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from transfertwin import InputError
from transfertwin.objects import load_object, merge_hulls


def _cube(x: float, y: float = 0.0, size: float = 0.01) -> np.ndarray:
    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float)
    return corners * size + np.array([x, y, 0.0])


def test_the_closest_pair_merges_first_and_features_stay_apart():
    # Cubes at x = 0, 0.01 (touching), 0.1 (far); a feature cube last.
    hulls = (_cube(0.0), _cube(0.1), _cube(0.01), _cube(0.0, 0.05, 0.005))
    out = merge_hulls(hulls, 2, keep_last=1)
    assert len(out) == 3
    volumes = sorted(ConvexHull(h).volume for h in out[:2])
    assert volumes == pytest.approx([1e-6, 2e-6])  # the two touching cubes became one box
    assert out[2] is hulls[3]


def test_within_budget_nothing_changes_and_a_zero_budget_is_refused():
    hulls = (_cube(0.0), _cube(0.1))
    assert merge_hulls(hulls, 2) == hulls
    with pytest.raises(InputError, match="budget"):
        merge_hulls(hulls, 0)


def test_a_core_keeps_its_outline_and_merging_is_deterministic():
    core = load_object("o1")
    body = len(core.hulls) - core.feature_hulls
    out = merge_hulls(core.hulls, 4, keep_last=core.feature_hulls)
    assert len(out) == 4 + core.feature_hulls < len(core.hulls) and body > 4
    before, after = np.concatenate(core.hulls), np.concatenate(out)
    np.testing.assert_array_equal(before.min(axis=0), after.min(axis=0))  # same AABB
    np.testing.assert_array_equal(before.max(axis=0), after.max(axis=0))
    again = merge_hulls(core.hulls, 4, keep_last=core.feature_hulls)
    assert all(np.array_equal(a, b) for a, b in zip(out, again, strict=True))
