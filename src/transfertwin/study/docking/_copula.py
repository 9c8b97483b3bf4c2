"""Synthetic docking-error generator: a Gaussian copula over (ξx, ξy, ξθ) (Sec. 6.4, Eq. 6.19).

Fit: each component gets a marginal F_i chosen by `fit_marginal` (criterion
``bic-ks-gate``, see `transfertwin.study.docking._marginals`); the dependence is the correlation
matrix ρ of the normal scores z = Φ⁻¹(r / (n + 1)), r the component's ranks (ties averaged).
Sample: z ~ N(0, ρ), u = Φ(z), x_i = F_i⁻¹(u_i) with every F_i truncated to its
marginal's bounds (the observed range widened by 10 % each side), so no value leaves them.

`PerStationCopula` fits one copula per transfer unit and draws the unit of each sample
with the unit frequencies of the fit data, so its pooled samples follow the pooled data.
Both models satisfy `DockingErrorModel`; `copula_from_dict` rebuilds them from
``describe()`` with every fitted parameter inline, so study plans stay reproducible.
Units: mm, mm, deg in arrays; `DockingError` (m, rad) from `sample`.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import special, stats

from transfertwin._errors import InputError
from transfertwin.sim import DockingError
from transfertwin.store import DOCKING_ERROR_COLUMNS
from transfertwin.study.docking._marginals import FAMILIES, KS_ALPHA, MarginalFamily, MarginalFit
from transfertwin.study.docking._marginals import fit_marginal as _fit_marginal

__all__ = [
    "COPULA_KINDS",
    "MIN_ROWS",
    "GaussianCopula",
    "PerStationCopula",
    "copula_from_dict",
    "normal_scores",
]

COLUMNS = DOCKING_ERROR_COLUMNS
COPULA_KINDS = ("copula", "copula-per-station")
MIN_ROWS = 10
_VERSION = 1


def _errors_array(data: np.ndarray, what: str = "docking errors") -> np.ndarray:
    x = np.asarray(data, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3:
        raise InputError(f"{what}: expected an (n, 3) array of x_mm, y_mm, theta_deg")
    if x.shape[0] < MIN_ROWS:
        raise InputError(f"{what}: need at least {MIN_ROWS} rows to fit a copula, got {len(x)}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{what}: values must be finite")
    return x


def _rng(seed: int) -> np.random.Generator:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed!r}")
    return np.random.default_rng(int(seed))


def _check_n(n: int) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise InputError(f"number of samples must be an integer >= 1, got {n!r}")
    return int(n)


def normal_scores(data: np.ndarray) -> np.ndarray:
    """Normal scores Φ⁻¹(r / (n + 1)) per column (n, d); r ranks with ties averaged."""
    x = np.asarray(data, dtype=float)
    return special.ndtri(stats.rankdata(x, axis=0) / (x.shape[0] + 1))


@dataclass(frozen=True)
class GaussianCopula:
    """Gaussian copula of the docking error (Eq. 6.19) with fitted marginals.

    Attributes:
        marginals: Fitted marginal of x (mm), y (mm) and θ (deg), with selection records.
        correlation: 3×3 correlation ρ of the normal scores (symmetric, positive definite).
        n_fit: Rows the model was fitted to.
    """

    marginals: tuple[MarginalFit, MarginalFit, MarginalFit]
    correlation: tuple[tuple[float, float, float], ...]
    n_fit: int

    def __post_init__(self) -> None:
        rho = np.asarray(self.correlation, dtype=float)
        if len(self.marginals) != 3 or rho.shape != (3, 3):
            raise InputError("copula: needs 3 marginals and a 3x3 correlation matrix")
        ok = np.all(np.isfinite(rho)) and np.allclose(rho, rho.T) and np.allclose(np.diag(rho), 1)
        if not ok or np.any(np.abs(rho) > 1):
            raise InputError("copula: correlation must be symmetric with unit diagonal")
        try:
            np.linalg.cholesky(rho)
        except np.linalg.LinAlgError:
            raise InputError("copula: correlation matrix is not positive definite") from None

    @cached_property
    def _chol(self) -> np.ndarray:
        return np.linalg.cholesky(np.asarray(self.correlation, dtype=float))

    @classmethod
    def fit(
        cls,
        data: np.ndarray,
        *,
        families: Sequence[MarginalFamily] = FAMILIES,
        ks_alpha: float = KS_ALPHA,
    ) -> GaussianCopula:
        """Fit marginals and the normal-score correlation to measured errors.

        Args:
            data: (n, 3) rows x_mm, y_mm, theta_deg; n >= `MIN_ROWS`.
            families: Candidate marginal families (tie-break order).
            ks_alpha: Level of the KS gate of the selection criterion.

        Raises:
            InputError: Bad shape, too few rows, non-finite values, or no family fits.
        """
        x = _errors_array(data)
        fits = tuple(
            _fit_marginal(x[:, j], c, families=families, ks_alpha=ks_alpha)
            for j, c in enumerate(COLUMNS)
        )
        rho = np.corrcoef(normal_scores(x), rowvar=False)
        if not np.all(np.isfinite(rho)):
            raise InputError("docking errors: correlation of normal scores is undefined")
        rows = tuple(tuple(float(v) for v in r) for r in rho)
        return cls(fits, rows, int(x.shape[0]))  # type: ignore[arg-type]

    def _draw(self, n: int, rng: np.random.Generator) -> np.ndarray:
        z = rng.standard_normal((n, 3)) @ self._chol.T
        u = special.ndtr(z)
        return np.column_stack([m.marginal.quantile(u[:, j]) for j, m in enumerate(self.marginals)])

    def sample_n(self, n: int, seed: int) -> np.ndarray:
        """``n`` synthetic errors (n, 3) in mm, mm, deg; a pure function of (n, seed)."""
        return self._draw(_check_n(n), _rng(seed))

    def sample(self, seed: int) -> DockingError:
        """One synthetic docking error, a pure function of ``seed``."""
        return DockingError.from_mm_deg(*(float(v) for v in self.sample_n(1, seed)[0]))

    def to_dict(self) -> dict[str, object]:
        """JSON-able model: kind ``copula``, ρ, and per column the winner, score and records."""
        return {
            "kind": "copula",
            "version": _VERSION,
            "n_fit": self.n_fit,
            "correlation": [list(r) for r in self.correlation],
            "marginals": [
                {"column": c, **m.to_dict()} for c, m in zip(COLUMNS, self.marginals, strict=True)
            ],
        }

    def describe(self) -> dict[str, object]:
        """Same as `to_dict` (the `DockingErrorModel` protocol)."""
        return self.to_dict()

    @classmethod
    def from_dict(cls, d: dict[str, object]) -> GaussianCopula:
        """Inverse of `to_dict`; `InputError` for a malformed description."""
        _check_kind(d, "copula")
        with _malformed("copula"):
            margs = tuple(MarginalFit.from_dict(m) for m in d["marginals"])  # type: ignore[union-attr]
            rho = tuple(tuple(float(v) for v in r) for r in d["correlation"])  # type: ignore[union-attr]
            return cls(margs, rho, int(d["n_fit"]))  # type: ignore[arg-type]


@dataclass(frozen=True)
class PerStationCopula:
    """One Gaussian copula per transfer unit; a sample's unit is drawn by data frequency.

    Attributes:
        units: Transfer-unit names, sorted.
        copulas: The copula of each unit (same order).
        counts: Rows of each unit in the fit data; unit probabilities are counts / sum.
    """

    units: tuple[str, ...]
    copulas: tuple[GaussianCopula, ...]
    counts: tuple[int, ...]

    def __post_init__(self) -> None:
        if not self.units or not len(self.units) == len(self.copulas) == len(self.counts):
            raise InputError("per-station copula: units, copulas and counts must match")
        if len(set(self.units)) != len(self.units) or min(self.counts) < 1:
            raise InputError("per-station copula: units must be unique with counts >= 1")

    @property
    def by_unit(self) -> dict[str, GaussianCopula]:
        """Unit name → its copula."""
        return dict(zip(self.units, self.copulas, strict=True))

    @classmethod
    def fit(
        cls,
        data: np.ndarray,
        units: Sequence[str],
        *,
        families: Sequence[MarginalFamily] = FAMILIES,
        ks_alpha: float = KS_ALPHA,
    ) -> PerStationCopula:
        """Fit one copula per unit; every unit needs at least `MIN_ROWS` rows.

        Args:
            data: (n, 3) rows x_mm, y_mm, theta_deg.
            units: (n,) transfer unit of each row.
        """
        x = np.asarray(data, dtype=float)
        labels = np.asarray([str(u) for u in units])
        if labels.shape != (x.shape[0],) or x.ndim != 2:
            raise InputError("per-station copula: need one transfer unit per row")
        names = tuple(sorted(set(labels.tolist())))
        copulas = tuple(
            GaussianCopula.fit(
                _errors_array(x[labels == u], f"unit {u}"), families=families, ks_alpha=ks_alpha
            )
            for u in names
        )
        return cls(names, copulas, tuple(int(np.sum(labels == u)) for u in names))

    def sample_with_units(self, n: int, seed: int) -> tuple[np.ndarray, tuple[str, ...]]:
        """``n`` errors (n, 3) in mm, mm, deg and the unit of each; pure in (n, seed)."""
        n, rng = _check_n(n), _rng(seed)
        p = np.asarray(self.counts, dtype=float) / sum(self.counts)
        idx = rng.choice(len(self.units), size=n, p=p)
        out = np.empty((n, 3))
        for k, cop in enumerate(self.copulas):
            mask = idx == k
            if mask.any():
                out[mask] = cop._draw(int(mask.sum()), rng)
        return out, tuple(self.units[i] for i in idx)

    def sample_n(self, n: int, seed: int) -> np.ndarray:
        """``n`` errors (n, 3) in mm, mm, deg (units drawn but not returned)."""
        return self.sample_with_units(n, seed)[0]

    def sample(self, seed: int) -> DockingError:
        """One docking error, a pure function of ``seed``."""
        return DockingError.from_mm_deg(*(float(v) for v in self.sample_n(1, seed)[0]))

    def to_dict(self) -> dict[str, object]:
        """JSON-able: kind ``copula-per-station`` and each unit's count and copula."""
        stations = [
            {"unit": u, "count": c, "copula": cop.to_dict()}
            for u, c, cop in zip(self.units, self.counts, self.copulas, strict=True)
        ]
        return {"kind": "copula-per-station", "version": _VERSION, "stations": stations}

    def describe(self) -> dict[str, object]:
        """Same as `to_dict` (the `DockingErrorModel` protocol)."""
        return self.to_dict()

    @classmethod
    def from_dict(cls, d: dict[str, object]) -> PerStationCopula:
        """Inverse of `to_dict`; `InputError` for a malformed description."""
        _check_kind(d, "copula-per-station")
        with _malformed("per-station copula"):
            st = list(d["stations"])  # type: ignore[call-overload]
            return cls(
                tuple(str(s["unit"]) for s in st),
                tuple(GaussianCopula.from_dict(s["copula"]) for s in st),
                tuple(int(s["count"]) for s in st),
            )


def copula_from_dict(desc: dict[str, object]) -> GaussianCopula | PerStationCopula:
    """Rebuild a copula model from ``describe()``/``to_dict()`` output (kinds `COPULA_KINDS`)."""
    if not isinstance(desc, dict):
        raise InputError("copula model: expected a JSON object")
    if desc.get("kind") == "copula-per-station":
        return PerStationCopula.from_dict(desc)
    return GaussianCopula.from_dict(desc)


def _check_kind(d: object, kind: str) -> None:
    if not isinstance(d, dict) or d.get("kind") != kind:
        got = d.get("kind") if isinstance(d, dict) else type(d).__name__
        raise InputError(f"copula model: expected kind {kind!r}, got {got!r}")
    if d.get("version") != _VERSION:
        raise InputError(f"copula model: unsupported version {d.get('version')!r}")


@contextmanager
def _malformed(what: str) -> Iterator[None]:
    """Turn a missing key or a wrong type in a model description into one `InputError` line."""
    try:
        yield
    except InputError:
        raise
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        msg = f"{what} model: malformed description ({type(exc).__name__}: {exc})"
        raise InputError(msg) from None
