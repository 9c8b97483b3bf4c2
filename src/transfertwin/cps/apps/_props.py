"""PropS: fusion of distributed 2-D pose estimates over a pose graph (Sec. 5.2).

Several assets report poses of the same subject, e.g. the docking pose of TM_1 seen by a
transfer unit's camera (relative to the unit) and by the robot's own localisation (in the
world frame). PropS finds the node poses that best explain all reports in the weighted
least-squares sense:

* a world observation of node s is a unary prior, residual (p_s ⊖ z) / σ;
* a relative observation of s in the frame of r is an edge, residual
  ((p_r⁻¹ ∘ p_s) ⊖ z) / σ;

with ⊖ the difference whose angle is wrapped to (-π, π] and σ = (σ_xy, σ_xy, σ_θ). If no
node has a world observation, the anchor node is fixed at the origin. The covariance of
the estimate is (JᵀJ)⁻¹ with J the Jacobian of the weighted residuals at the solution.
Units: metres and radians.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from transfertwin._errors import InputError

__all__ = [
    "Pose2D",
    "PoseGraph",
    "PoseGraphSolution",
    "PoseObservation",
    "fuse_poses",
    "wrap_angle",
]


def wrap_angle(angle: float) -> float:
    """Angle wrapped to (-π, π], radians."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


@dataclass(frozen=True)
class Pose2D:
    """A planar pose: position (m) and heading (rad) of a frame in its parent frame."""

    x: float
    y: float
    theta: float

    def compose(self, other: Pose2D) -> Pose2D:
        """``self ∘ other``: ``other`` (given in this frame) expressed in the parent frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            wrap_angle(self.theta + other.theta),
        )

    def inverse(self) -> Pose2D:
        """The parent frame expressed in this frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(-c * self.x - s * self.y, s * self.x - c * self.y, wrap_angle(-self.theta))

    def as_array(self) -> np.ndarray:
        """``[x, y, theta]``, shape (3,)."""
        return np.array([self.x, self.y, self.theta])


@dataclass(frozen=True)
class PoseObservation:
    """One pose estimate reported by an asset.

    Attributes:
        source: Reporting asset, e.g. 'TU_C' (its camera) or 'TM_1' (its localisation).
        subject: Node whose pose is observed, e.g. 'TM_1'.
        x: Position x, m.
        y: Position y, m.
        theta: Heading, rad.
        sigma_xy: Standard deviation of x and of y, m (> 0).
        sigma_theta: Standard deviation of theta, rad (> 0).
        relative_to: None for a world-frame pose, else the node in whose frame the pose
            of ``subject`` is given (an edge relative_to → subject).
    """

    source: str
    subject: str
    x: float
    y: float
    theta: float
    sigma_xy: float
    sigma_theta: float
    relative_to: str | None = None

    def __post_init__(self) -> None:
        for name in ("source", "subject"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name):
                raise InputError(f"PoseObservation.{name} must be a non-empty string")
        if self.relative_to is not None and self.relative_to in ("", self.subject):
            raise InputError(f"{self.subject}: relative_to must name another node")
        for name in ("x", "y", "theta", "sigma_xy", "sigma_theta"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"{self.subject}: {name} must be finite")
        if self.sigma_xy <= 0.0 or self.sigma_theta <= 0.0:
            raise InputError(
                f"{self.subject} (from {self.source}): sigmas must be > 0, "
                f"got sigma_xy={self.sigma_xy}, sigma_theta={self.sigma_theta}"
            )

    @property
    def pose(self) -> Pose2D:
        """The observed pose."""
        return Pose2D(self.x, self.y, self.theta)


@dataclass(frozen=True)
class PoseGraphSolution:
    """The fused estimate of all nodes.

    Attributes:
        poses: Node -> pose in the world frame (or the anchor's frame), theta in (-π, π].
        covariances: Node -> covariance of (x, y, theta), shape (3, 3); zero for the anchor.
        residual_norm: Euclidean norm of the weighted residual vector (dimensionless).
        anchor: Node fixed at the origin, or None when world observations fix the frame.
        converged: Whether the solver reported convergence.
        joint: The joint covariance of every free node's (x, y, theta), shape (3N, 3N).
        index: Node -> its block in `joint` (the anchor has none: it is fixed).
    """

    poses: dict[str, Pose2D]
    covariances: dict[str, np.ndarray] = field(repr=False)
    residual_norm: float
    anchor: str | None
    converged: bool
    joint: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    index: dict[str, int] = field(default_factory=dict, repr=False)

    def relative(self, parent: str, child: str) -> tuple[Pose2D, np.ndarray]:
        """The fused pose of `child` in the frame of `parent` (``parent⁻¹ ∘ child``) and its
        covariance, shape (3, 3), to first order from the joint covariance (the two
        estimates are correlated through the observations they share).

        Raises:
            InputError: A node not in the graph.
        """
        for node in (parent, child):
            if node not in self.poses:
                raise InputError(f"unknown pose-graph node {node!r}")
        pp, pc = self.poses[parent].as_array(), self.poses[child].as_array()
        c, s = math.cos(pp[2]), math.sin(pp[2])
        dx, dy = pc[0] - pp[0], pc[1] - pp[1]
        rel = Pose2D(c * dx + s * dy, -s * dx + c * dy, wrap_angle(pc[2] - pp[2]))
        d_child = np.eye(3)
        d_child[:2, :2] = [[c, s], [-s, c]]
        d_parent = -np.eye(3)
        d_parent[:2, :2] = [[-c, -s], [s, -c]]
        d_parent[:2, 2] = [-s * dx + c * dy, -c * dx - s * dy]
        jac = np.zeros((3, self.joint.shape[0]))
        for node, d in ((parent, d_parent), (child, d_child)):
            if node in self.index:
                i = self.index[node]
                jac[:, 3 * i : 3 * i + 3] += d
        return rel, jac @ self.joint @ jac.T


def _nodes(observations: Sequence[PoseObservation]) -> list[str]:
    names: dict[str, None] = {}
    for obs in observations:
        if obs.relative_to is not None:
            names.setdefault(obs.relative_to)
        names.setdefault(obs.subject)
    return list(names)


def _reachable(observations: Sequence[PoseObservation], roots: set[str]) -> set[str]:
    """Nodes linked to ``roots`` by relative edges (in either direction)."""
    links: dict[str, set[str]] = {}
    for obs in observations:
        if obs.relative_to is not None:
            links.setdefault(obs.subject, set()).add(obs.relative_to)
            links.setdefault(obs.relative_to, set()).add(obs.subject)
    seen, todo = set(roots), list(roots)
    while todo:
        for nxt in links.get(todo.pop(), set()) - seen:
            seen.add(nxt)
            todo.append(nxt)
    return seen


def _initial_poses(
    observations: Sequence[PoseObservation], anchor: str | None
) -> dict[str, Pose2D]:
    """Start poses: first world observation or the anchor, spread along the edges."""
    known: dict[str, Pose2D] = {} if anchor is None else {anchor: Pose2D(0.0, 0.0, 0.0)}
    for obs in observations:
        if obs.relative_to is None:
            known.setdefault(obs.subject, obs.pose)
    edges = [obs for obs in observations if obs.relative_to is not None]
    grown = True
    while grown:
        grown = False
        for obs in edges:
            parent, child = obs.relative_to, obs.subject
            if parent in known and child not in known:
                known[child] = known[parent].compose(obs.pose)
                grown = True
            elif child in known and parent not in known:
                known[parent] = known[child].compose(obs.pose.inverse())
                grown = True
    return known


def _residuals(
    observations: Sequence[PoseObservation], index: dict[str, int], params: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted residuals, shape (3M,), and their Jacobian, shape (3M, 3N).

    Nodes not in ``index`` (the anchor) sit at the origin.
    """
    res = np.zeros(3 * len(observations))
    jac = np.zeros((3 * len(observations), params.size))

    def pose(node: str) -> np.ndarray:
        return params[3 * index[node] : 3 * index[node] + 3] if node in index else np.zeros(3)

    for k, obs in enumerate(observations):
        rows = slice(3 * k, 3 * k + 3)
        w = np.array([1.0 / obs.sigma_xy, 1.0 / obs.sigma_xy, 1.0 / obs.sigma_theta])
        ps = pose(obs.subject)
        d_subject = np.eye(3)
        d_parent = None
        if obs.relative_to is None:
            pred = ps
        else:
            pr = pose(obs.relative_to)
            c, s = math.cos(pr[2]), math.sin(pr[2])
            dx, dy = ps[0] - pr[0], ps[1] - pr[1]
            rot_t = np.array([[c, s], [-s, c]])
            pred = np.array([c * dx + s * dy, -s * dx + c * dy, ps[2] - pr[2]])
            d_subject[:2, :2] = rot_t
            d_parent = -np.eye(3)
            d_parent[:2, :2] = -rot_t
            d_parent[:2, 2] = [-s * dx + c * dy, -c * dx - s * dy]
        diff = pred - obs.pose.as_array()
        diff[2] = wrap_angle(float(diff[2]))
        res[rows] = w * diff
        if obs.subject in index:
            cols = slice(3 * index[obs.subject], 3 * index[obs.subject] + 3)
            jac[rows, cols] += w[:, None] * d_subject
        if d_parent is not None and obs.relative_to in index:
            cols = slice(3 * index[obs.relative_to], 3 * index[obs.relative_to] + 3)
            jac[rows, cols] += w[:, None] * d_parent
    return res, jac


def fuse_poses(
    observations: Sequence[PoseObservation], anchor: str | None = None
) -> PoseGraphSolution:
    """Least-squares fusion of pose observations (PropS, Sec. 5.2).

    Args:
        observations: World-frame priors and relative edges.
        anchor: Node fixed at the origin; required if and only if no observation is in
            the world frame.

    Returns:
        The fused poses, their covariances and the residual norm.

    Raises:
        InputError: No observations, an unknown or superfluous anchor, a missing
            anchor, or a node not connected to a world observation or the anchor.
    """
    if not observations:
        raise InputError("PropS needs at least one pose observation")
    nodes = _nodes(observations)
    world = {obs.subject for obs in observations if obs.relative_to is None}
    if anchor is not None and anchor not in nodes:
        raise InputError(f"unknown anchor {anchor!r}; nodes: {sorted(nodes)}")
    if world and anchor is not None:
        raise InputError("world observations fix the frame; pass no anchor")
    if not world and anchor is None:
        raise InputError("no world observation: name an anchor node to fix at the origin")
    roots = world or {anchor}
    loose = sorted(set(nodes) - _reachable(observations, roots))
    if loose:
        raise InputError(f"nodes {loose} are linked to no world observation nor the anchor")
    free = [n for n in nodes if n != anchor]
    index = {n: i for i, n in enumerate(free)}
    start = _initial_poses(observations, anchor)
    x0 = np.concatenate([start[n].as_array() for n in free])
    result = least_squares(
        lambda p: _residuals(observations, index, p)[0],
        x0,
        jac=lambda p: _residuals(observations, index, p)[1],
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
    )
    r, j = _residuals(observations, index, result.x)
    cov = np.linalg.inv(j.T @ j)
    poses = {anchor: Pose2D(0.0, 0.0, 0.0)} if anchor is not None else {}
    covs = {anchor: np.zeros((3, 3))} if anchor is not None else {}
    for n, i in index.items():
        x, y, theta = result.x[3 * i : 3 * i + 3]
        poses[n] = Pose2D(float(x), float(y), wrap_angle(float(theta)))
        covs[n] = cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3].copy()
    return PoseGraphSolution(
        poses=poses,
        covariances=covs,
        residual_norm=float(np.linalg.norm(r)),
        anchor=anchor,
        converged=bool(result.success),
        joint=cov,
        index=dict(index),
    )


class PoseGraph:
    """Mutable collection of observations over `fuse_poses` (the PropS asset's state).

    `fused`, `covariance` and `residual_norm` refer to the latest `solve`, re-solving with
    the same anchor if observations were added since.
    """

    def __init__(self) -> None:
        self._observations: list[PoseObservation] = []
        self._anchor: str | None = None
        self._solution: PoseGraphSolution | None = None

    @property
    def observations(self) -> tuple[PoseObservation, ...]:
        """All observations added so far, in order."""
        return tuple(self._observations)

    def add(self, obs: PoseObservation) -> None:
        """Add one observation."""
        if not isinstance(obs, PoseObservation):
            raise InputError(f"expected a PoseObservation, got {type(obs).__name__}")
        self._observations.append(obs)
        self._solution = None

    def put(self, obs: PoseObservation) -> None:
        """Add `obs` in place of the earlier observation of the same source, subject and
        frame, if any (a graph of current estimates, not of a trajectory)."""
        key = (obs.source, obs.subject, obs.relative_to)
        self.drop(lambda o: (o.source, o.subject, o.relative_to) == key)
        self.add(obs)

    def drop(self, which) -> int:
        """Remove the observations for which ``which(obs)`` is true; how many."""
        kept = [o for o in self._observations if not which(o)]
        dropped = len(self._observations) - len(kept)
        if dropped:
            self._observations = kept
            self._solution = None
        return dropped

    def solve(self, anchor: str | None = None) -> dict[str, Pose2D]:
        """Fuse all observations; see `fuse_poses`. Returns node -> pose."""
        self._solution = fuse_poses(self._observations, anchor)
        self._anchor = anchor
        return dict(self._solution.poses)

    def solution(self) -> PoseGraphSolution:
        """The current solution (solved on demand with the last anchor)."""
        if self._solution is None:
            self._solution = fuse_poses(self._observations, self._anchor)
        return self._solution

    def fused(self, subject: str) -> Pose2D:
        """Fused pose of ``subject``."""
        return self.solution().poses[self._check(subject)]

    def covariance(self, subject: str) -> np.ndarray:
        """Covariance of the fused (x, y, theta) of ``subject``, shape (3, 3)."""
        return self.solution().covariances[self._check(subject)].copy()

    @property
    def residual_norm(self) -> float:
        """Norm of the weighted residuals at the solution."""
        return self.solution().residual_norm

    def _check(self, subject: str) -> str:
        if subject not in _nodes(self._observations):
            raise InputError(f"unknown pose-graph node {subject!r}")
        return subject
