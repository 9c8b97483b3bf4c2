"""Pieces every command group shares: the one-line-error parser and argument parsers."""

from __future__ import annotations

import argparse
import os

from transfertwin._errors import InputError

__all__ = ["Parser", "parse_dock_error", "positive_int", "worker_count"]


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InputError(message)


def parse_dock_error(text: str):  # -> DockingError
    """``X_MM,Y_MM,THETA_DEG`` → a docking error ξ (Eq. 6.11)."""
    from transfertwin.sim import DockingError

    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 3:
        raise InputError(f"--dock-error expects X_MM,Y_MM,THETA_DEG, got {text!r}")
    return DockingError.from_mm_deg(*values)


def positive_int(option: str, value: int) -> int:
    """`value` if it is at least 1, else an InputError naming `option`."""
    if value < 1:
        raise InputError(f"{option} must be at least 1, got {value}")
    return value


def worker_count(value: int | None) -> int:
    """``--workers``: at least 1; None means one per CPU core."""
    if value is None:
        return os.cpu_count() or 1
    return positive_int("--workers", value)
