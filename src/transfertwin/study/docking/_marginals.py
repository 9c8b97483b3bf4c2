"""Marginal distributions F_i of the docking-error copula and how one is chosen (Sec. 6.4).

Candidate families (`FAMILIES`): normal, truncated normal, beta, Student t, gamma (with a
location), uniform and a Gaussian kernel density estimate (KDE). Every fit is deterministic
(closed forms, or scipy's optimisers from fixed starting points).

Selection criterion ``"bic-ks-gate"`` (one rule, recorded in every `MarginalFit`):

1. Each parametric family is fitted by maximum likelihood and scored by
   BIC = k ln n − 2 ln L̂, k counting every quantity estimated from the data (the
   support bounds of beta and truncated normal included).
2. A one-sample Kolmogorov–Smirnov test of the fitted CDF against the data gates it:
   a family with p < ``ks_alpha`` (default 0.05) is *rejected*. With estimated
   parameters the test is conservative, so it only removes clearly wrong shapes.
3. The lowest BIC among the families that pass wins (ties: the earlier family).
4. Only if no parametric family passes, the KDE wins (it has no likelihood-based BIC;
   its KS statistic is recorded as its score).

A family whose fit raises or gives non-finite values is recorded as ``"failed"`` with
the reason and skipped, never replaced silently; if nothing is left, `InputError`.

Bounds: every marginal carries ``bounds`` = the observed range widened by
``RANGE_MARGIN`` (10 %) of its width on each side. Beta and truncated normal use them as
their support; `Marginal.quantile` samples each family truncated to them, so synthetic
values never leave the bounds. Values are in the data's units (mm or deg).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from functools import cached_property
from typing import Protocol

import numpy as np
from scipy import optimize, special, stats

from transfertwin._errors import InputError

__all__ = [
    "CRITERION",
    "FAMILIES",
    "KS_ALPHA",
    "RANGE_MARGIN",
    "CandidateFit",
    "Marginal",
    "MarginalFamily",
    "MarginalFit",
    "fit_marginal",
    "marginal_family",
]

CRITERION = "bic-ks-gate"
KS_ALPHA = 0.05
RANGE_MARGIN = 0.1
_KDE_GRID = 4097  # points of the KDE's quantile grid
_KDE_TAIL = 8.0  # the grid reaches this many bandwidths beyond the data


class _Dist(Protocol):
    def cdf(self, x: np.ndarray) -> np.ndarray: ...
    def ppf(self, q: np.ndarray) -> np.ndarray: ...
    def logpdf(self, x: np.ndarray) -> np.ndarray: ...


class _KdeDist:
    """Gaussian KDE (Scott bandwidth) with its exact CDF and a monotone grid-interpolated PPF."""

    def __init__(self, points: Sequence[float], factor: float) -> None:
        self._kde = stats.gaussian_kde(np.asarray(points, dtype=float), bw_method=factor)
        self._h = float(np.sqrt(self._kde.covariance[0, 0]))  # bandwidth, data units

    @cached_property
    def _ppf_grid(self) -> tuple[np.ndarray, np.ndarray]:
        pts = self._kde.dataset[0]
        x = np.linspace(pts.min() - _KDE_TAIL * self._h, pts.max() + _KDE_TAIL * self._h, _KDE_GRID)
        c = self.cdf(x)
        keep = np.concatenate(([True], np.diff(c) > 0))  # strictly increasing for np.interp
        return c[keep], x[keep]

    def cdf(self, x: np.ndarray) -> np.ndarray:
        """mean_i Φ((x − p_i) / h): `gaussian_kde.integrate_box_1d(-inf, x)`, vectorised."""
        flat, pts, h = np.ravel(np.asarray(x, dtype=float)), self._kde.dataset[0], self._h
        step = max(1, 4_000_000 // pts.size)  # bound the (chunk, n) temporary
        out = [
            special.ndtr((flat[i : i + step, None] - pts[None, :]) / h).mean(axis=1)
            for i in range(0, flat.size, step)
        ]
        return np.concatenate(out or [np.empty(0)]).reshape(np.shape(x))

    def ppf(self, q: np.ndarray) -> np.ndarray:
        return np.interp(q, *self._ppf_grid)

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        return self._kde.logpdf(np.asarray(x, dtype=float))


@dataclass(frozen=True)
class MarginalFamily:
    """One candidate family.

    Attributes:
        name: Identifier stored in model files.
        param_names: Names of ``params`` in order.
        n_free: Parameters counted by BIC (data-derived bounds included).
        fit: ``fit(values (n,), bounds (lo, hi)) -> params``; raises on failure.
        build: ``build(params, points) -> distribution`` with cdf, ppf and logpdf.
        parametric: False for the KDE (no BIC; chosen only as the fallback).
    """

    name: str
    param_names: tuple[str, ...]
    n_free: int
    fit: Callable[[np.ndarray, tuple[float, float]], tuple[float, ...]]
    build: Callable[[tuple[float, ...], tuple[float, ...]], _Dist]
    parametric: bool = True


def _spread(x: np.ndarray) -> float:
    s = float(np.std(x))
    if not s > 0:
        raise ValueError("zero spread")
    return s


def _fit_truncnorm(x: np.ndarray, b: tuple[float, float]) -> tuple[float, ...]:
    lo, hi = b

    def nll(p: np.ndarray) -> float:
        s = math.exp(p[1])
        return -float(np.sum(stats.truncnorm.logpdf(x, (lo - p[0]) / s, (hi - p[0]) / s, p[0], s)))

    res = optimize.minimize(nll, [float(np.mean(x)), math.log(_spread(x))], method="Nelder-Mead")
    if not res.success:
        raise ValueError(f"optimiser did not converge: {res.message}")
    return float(res.x[0]), math.exp(float(res.x[1])), lo, hi


def _fit_beta(x: np.ndarray, b: tuple[float, float]) -> tuple[float, ...]:
    a, bb, loc, scale = stats.beta.fit(x, floc=b[0], fscale=b[1] - b[0])
    return float(a), float(bb), float(loc), float(scale)


def _fit_kde(x: np.ndarray, b: tuple[float, float]) -> tuple[float, ...]:
    _spread(x)
    return (float(stats.gaussian_kde(x).factor),)


_F = MarginalFamily
FAMILIES: tuple[MarginalFamily, ...] = (
    _F("normal", ("loc", "scale"), 2, lambda x, b: (float(np.mean(x)), _spread(x)),
       lambda p, _: stats.norm(p[0], p[1])),
    _F("truncnorm", ("loc", "scale", "lower", "upper"), 4, _fit_truncnorm,
       lambda p, _: stats.truncnorm((p[2] - p[0]) / p[1], (p[3] - p[0]) / p[1], p[0], p[1])),
    _F("beta", ("a", "b", "loc", "scale"), 4, _fit_beta, lambda p, _: stats.beta(*p)),
    _F("student_t", ("df", "loc", "scale"), 3, lambda x, b: stats.t.fit(x),
       lambda p, _: stats.t(*p)),
    _F("gamma", ("a", "loc", "scale"), 3, lambda x, b: stats.gamma.fit(x),
       lambda p, _: stats.gamma(*p)),
    _F("uniform", ("loc", "scale"), 2, lambda x, b: (float(np.min(x)), float(np.ptp(x))),
       lambda p, _: stats.uniform(*p)),
    _F("kde", ("bw_factor",), 0, _fit_kde, lambda p, pts: _KdeDist(pts, p[0]), parametric=False),
)  # fmt: skip


def marginal_family(name: str) -> MarginalFamily:
    """The built-in family called ``name``; `InputError` if there is none."""
    for fam in FAMILIES:
        if fam.name == name:
            return fam
    raise InputError(
        f"unknown marginal family {name!r} (known: {', '.join(f.name for f in FAMILIES)})"
    )


@dataclass(frozen=True)
class Marginal:
    """A fitted marginal F_i (Eq. 6.19), truncated to ``bounds`` when sampled.

    Attributes:
        family: Name of a family in `FAMILIES`.
        params: Its parameters, in the family's ``param_names`` order (data units).
        bounds: (lower, upper) limits of synthetic values, data units.
        points: The data behind a KDE (empty for parametric families).
    """

    family: str
    params: tuple[float, ...]
    bounds: tuple[float, float]
    points: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        fam = marginal_family(self.family)
        if len(self.params) != len(fam.param_names):
            raise InputError(f"marginal {self.family}: expected params {fam.param_names}")
        values = (*self.params, *self.bounds, *self.points)
        if not all(math.isfinite(v) for v in values) or not self.bounds[0] < self.bounds[1]:
            raise InputError(f"marginal {self.family}: params and bounds must be finite, lo < hi")
        if not fam.parametric and len(self.points) < 2:
            raise InputError(f"marginal {self.family}: needs at least 2 points")
        with np.errstate(all="ignore"):
            f_lo, f_hi = self._cdf_bounds
        if not (math.isfinite(f_lo) and math.isfinite(f_hi) and f_hi > f_lo):
            raise InputError(f"marginal {self.family}: parameters put no probability in bounds")

    @cached_property
    def dist(self) -> _Dist:
        """The untruncated distribution (cdf, ppf, logpdf)."""
        return marginal_family(self.family).build(self.params, self.points)

    @cached_property
    def _cdf_bounds(self) -> tuple[float, float]:
        lo, hi = (float(v) for v in self.dist.cdf(np.array(self.bounds)))
        return lo, hi

    def quantile(self, u: np.ndarray) -> np.ndarray:
        """Quantiles of the marginal truncated to ``bounds``: u ∈ [0, 1] → values in bounds."""
        f_lo, f_hi = self._cdf_bounds
        with np.errstate(divide="ignore"):  # ppf(1) = inf for unbounded families: clipped
            x = self.dist.ppf(f_lo + np.asarray(u, dtype=float) * (f_hi - f_lo))
        return np.clip(x, *self.bounds)

    def to_dict(self) -> dict[str, object]:
        """JSON-able: family, params by name, bounds (and points for a KDE)."""
        names = marginal_family(self.family).param_names
        out = {"family": self.family, "params": dict(zip(names, self.params, strict=True)),
               "bounds": list(self.bounds)}  # fmt: skip
        return {**out, "points": list(self.points)} if self.points else out

    @classmethod
    def from_dict(cls, d: dict[str, object]) -> Marginal:
        """Inverse of `to_dict`."""
        fam = marginal_family(str(d["family"]))
        params = d["params"]
        if not isinstance(params, dict) or set(params) != set(fam.param_names):
            raise InputError(f"marginal {fam.name}: params must be {list(fam.param_names)}")
        lo, hi = (float(v) for v in d["bounds"])  # type: ignore[union-attr]
        pts = tuple(float(v) for v in d.get("points", ()))  # type: ignore[union-attr]
        return cls(fam.name, tuple(float(params[k]) for k in fam.param_names), (lo, hi), pts)


@dataclass(frozen=True)
class CandidateFit:
    """How one family fared. status: ``fitted``, ``rejected`` (KS gate) or ``failed``."""

    family: str
    status: str
    bic: float | None = None
    ks_statistic: float | None = None
    ks_pvalue: float | None = None
    reason: str = ""

    def to_dict(self) -> dict[str, object]:
        """JSON-able record."""
        return asdict(self)

    def rejected(self, alpha: float) -> CandidateFit:
        """This record turned down by the KS gate at level ``alpha``."""
        why = f"KS p = {self.ks_pvalue:.3g} < {alpha}"
        return CandidateFit(
            self.family, "rejected", self.bic, self.ks_statistic, self.ks_pvalue, why
        )


@dataclass(frozen=True)
class MarginalFit:
    """The winning marginal, every candidate's record and the criterion that chose."""

    marginal: Marginal
    candidates: tuple[CandidateFit, ...]
    criterion: str = CRITERION
    ks_alpha: float = KS_ALPHA

    @property
    def score(self) -> CandidateFit:
        """The winner's record (BIC and KS)."""
        return next(c for c in self.candidates if c.family == self.marginal.family)

    def to_dict(self) -> dict[str, object]:
        """The winner (family, params, bounds), its score, the criterion and all candidates."""
        out = self.marginal.to_dict()
        out["score"] = {"bic": self.score.bic, "ks_statistic": self.score.ks_statistic,
                        "ks_pvalue": self.score.ks_pvalue}  # fmt: skip
        out["criterion"] = {"name": self.criterion, "ks_alpha": self.ks_alpha}
        out["candidates"] = [c.to_dict() for c in self.candidates]
        return out

    @classmethod
    def from_dict(cls, d: dict[str, object]) -> MarginalFit:
        """Inverse of `to_dict`."""
        crit = d["criterion"]
        if not isinstance(crit, dict):
            raise InputError("marginal: criterion must be an object")
        cands = tuple(CandidateFit(**c) for c in d["candidates"])  # type: ignore[union-attr]
        return cls(Marginal.from_dict(d), cands, str(crit["name"]), float(crit["ks_alpha"]))


def _try_family(
    fam: MarginalFamily, x: np.ndarray, bounds: tuple[float, float]
) -> tuple[CandidateFit, tuple[float, ...]]:
    """Fit and score one family; failures become a ``failed`` record with the reason."""
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            params = tuple(float(v) for v in fam.fit(x, bounds))
            if not all(math.isfinite(v) for v in params):
                raise ValueError(f"non-finite parameters {params}")
            dist = fam.build(params, () if fam.parametric else tuple(float(v) for v in x))
            loglik = float(np.sum(dist.logpdf(x))) if fam.parametric else 0.0
            if not math.isfinite(loglik):
                raise ValueError("log-likelihood is not finite on the data")
            ks = stats.kstest(x, dist.cdf)
    except Exception as exc:  # any fit error is recorded, not raised
        return CandidateFit(fam.name, "failed", reason=f"{type(exc).__name__}: {exc}"), ()
    bic = fam.n_free * math.log(len(x)) - 2.0 * loglik if fam.parametric else None
    return CandidateFit(fam.name, "fitted", bic, float(ks.statistic), float(ks.pvalue)), params


def fit_marginal(
    values: np.ndarray,
    name: str = "values",
    *,
    families: Sequence[MarginalFamily] = FAMILIES,
    ks_alpha: float = KS_ALPHA,
) -> MarginalFit:
    """Fit every family to ``values`` and choose one by the ``bic-ks-gate`` criterion.

    Args:
        values: Observations (n,), data units (mm or deg).
        name: Column name for error messages.
        families: Candidates, in tie-break order.
        ks_alpha: Level of the KS gate on parametric families.

    Raises:
        InputError: Non-finite or constant values, or no family fits.
    """
    x = np.asarray(values, dtype=float).ravel()
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name}: values must be finite")
    if x.size < 2 or np.ptp(x) == 0:
        raise InputError(f"{name}: needs at least 2 distinct values to fit a distribution")
    width = float(np.ptp(x))
    bounds = (float(x.min()) - RANGE_MARGIN * width, float(x.max()) + RANGE_MARGIN * width)
    records, params = [], {}
    for fam in families:
        rec, par = _try_family(fam, x, bounds)
        if rec.status == "fitted" and fam.parametric and rec.ks_pvalue < ks_alpha:
            rec = rec.rejected(ks_alpha)
        records.append(rec)
        params[fam.name] = par
    ok = [(r, f) for r, f in zip(records, families, strict=True) if r.status == "fitted"]
    pool = [rf for rf in ok if rf[1].parametric] or [rf for rf in ok if not rf[1].parametric]
    if not pool:
        why = "; ".join(f"{r.family} {r.status} ({r.reason})" for r in records)
        raise InputError(f"{name}: no marginal family fits: {why}")
    _, fam = min(pool, key=lambda rf: rf[0].bic if rf[0].bic is not None else 0.0)
    pts = () if fam.parametric else tuple(float(v) for v in x)
    winner = Marginal(fam.name, params[fam.name], bounds, pts)
    return MarginalFit(winner, tuple(records), CRITERION, ks_alpha)
