"""The docking-error generator a floor samples when a module is put at a station
(``docking = "sampled"``) and that the twin's predictions draw from: the Gaussian copula
fitted to the measured docking errors (Sec. 6.4)."""

from __future__ import annotations

import functools

from transfertwin.study.docking import GaussianCopula, measured_docking_errors

__all__ = ["docking_model"]


@functools.cache
def docking_model() -> GaussianCopula:
    """The generator fitted to the measured errors (deterministic; fitted once per process,
    about 0.6 s)."""
    return GaussianCopula.fit(measured_docking_errors())
