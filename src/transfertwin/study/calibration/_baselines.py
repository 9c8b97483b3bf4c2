"""Statistical baselines of the real outcomes: rate tables per cell, with and without
shrinkage, fitted on training rows only.

A *cell* is a key per row, e.g. 'o1|back' (object, face) or 'o1|back|left' (object, face,
conveyor). Shapes: `keys` (n,) strings, `y` (n,) 0/1, `train` row indices; every function
returns P(success) for all n rows.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["cell_keys", "rate_table", "shrunk_rate_table"]

_EPS = 1e-6


def cell_keys(rows: Sequence[Mapping[str, object]], columns: Sequence[str]) -> np.ndarray:
    """Each row's cell, the values of `columns` joined by '|' (n,)."""
    return np.array(["|".join(str(r[c]) for c in columns) for r in rows])


def rate_table(keys: np.ndarray, y: np.ndarray, train: np.ndarray) -> np.ndarray:
    """The success share of each row's cell among the `train` rows; a cell without training
    rows gets the training base rate."""
    keys, y = np.asarray(keys), np.asarray(y, dtype=float)
    p = np.full(len(keys), float(y[train].mean()))
    for key in np.unique(keys[train]):
        mine = train[keys[train] == key]
        p[keys == key] = y[mine].mean()
    return p


def _loo_loss(m: float, k: np.ndarray, n: np.ndarray, parent: np.ndarray,
              y: np.ndarray) -> float:  # fmt: skip
    """Leave-one-out log-loss of the shrunk cell rates on the training rows (per row: its
    cell's successes k and size n without itself, its parent rate)."""
    q = (k - y + m * parent) / (n - 1 + m)
    q = np.clip(q, _EPS, 1 - _EPS)
    return -float(np.mean(y * np.log(q) + (1 - y) * np.log(1 - q)))


def shrunk_rate_table(
    keys: np.ndarray, parents: np.ndarray, y: np.ndarray, train: np.ndarray
) -> tuple[np.ndarray, float]:
    """Cell rates shrunk towards their parent cell's rate (empirical Bayes), and the prior
    weight m.

    P(cell) = (k + m · P(parent)) / (n + m) with k successes among the cell's n training
    rows and P(parent) the parent's `rate_table` (e.g. (object, face) for an (object, face,
    conveyor) cell); m > 0 is chosen on the training rows alone by the leave-one-out
    log-loss (scipy's bounded scalar minimiser over log m in [-3, 6]). A cell without
    training rows gets its parent's rate.
    """
    from scipy.optimize import minimize_scalar

    keys, parents = np.asarray(keys), np.asarray(parents)
    y = np.asarray(y, dtype=float)
    parent_p = rate_table(parents, y, train)
    kt = keys[train]
    uniq, inverse = np.unique(kt, return_inverse=True)
    k_cell = np.bincount(inverse, weights=y[train])
    n_cell = np.bincount(inverse).astype(float)
    k, n, yt, par = k_cell[inverse], n_cell[inverse], y[train], parent_p[train]
    res = minimize_scalar(lambda lm: _loo_loss(float(np.exp(lm)), k, n, par, yt),
                          bounds=(-3.0, 6.0), method="bounded")  # fmt: skip
    m = float(np.exp(res.x))
    p = parent_p.copy()
    for j, key in enumerate(uniq):
        mask = keys == key
        p[mask] = (k_cell[j] + m * parent_p[mask]) / (n_cell[j] + m)
    return p, m
