"""Pieces every command group shares: the one-line-error parser and argument parsers."""

from __future__ import annotations

import argparse
import functools
import os
from collections.abc import Callable

from transfertwin._errors import InputError

__all__ = [
    "Parser",
    "add_executor_args",
    "add_state_args",
    "executor_from_args",
    "parse_positions",
    "positive_int",
    "with_executor",
    "worker_count",
]


def parse_positions(text: str, option: str = "--positions") -> tuple[float, ...]:
    """Protrusion positions along an object's x axis, ``X1,X2,...`` as fractions of its
    length in 0..1."""
    try:
        values = tuple(float(p) for p in text.split(",") if p.strip())
    except ValueError:
        values = ()
    if not values or not all(0.0 <= v <= 1.0 for v in values):
        raise InputError(f"{option} expects fractions X1,X2,... in 0..1, got {text!r}")
    return values


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InputError(message)


def add_state_args(p: argparse.ArgumentParser) -> None:
    """The object and its pre-transfer state: --object, --units, --face, --conveyor, --theta
    and --dock-error (the options `transfer` and `perceive` share)."""
    p.add_argument("--object", required=True, help="built-in core id (o1..o37) or a mesh path")
    p.add_argument("--units", default="m", help="length unit of a mesh file: m, cm, mm, in")
    p.add_argument("--face", required=True, help="front or back")
    p.add_argument("--conveyor", required=True, help="left, right or both")
    p.add_argument("--theta", required=True, type=int, help="yaw in integer degrees, -179..180")
    p.add_argument("--dock-error", default="0,0,0", help="X_MM,Y_MM,THETA_DEG (default 0,0,0)")


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


def add_executor_args(p: argparse.ArgumentParser, warp: bool = False) -> None:
    """``--executor local|ray`` (and ``warp`` where `warp`), ``--address`` and
    ``--chunk-size`` (docs/scaling.md)."""
    choices = ("local", "ray", "warp") if warp else ("local", "ray")
    extra = "; warp: batched MuJoCo Warp worlds on a CUDA GPU" if warp else ""
    p.add_argument("--executor", choices=choices, default="local",
                   help=f"local processes (default) or Ray tasks{extra} "
                   "(docs/scaling.md)")  # fmt: skip
    p.add_argument("--address", help="with --executor ray: auto or HOST:PORT of a running "
                   "Ray cluster (default: start a local Ray with --workers CPUs)")  # fmt: skip
    chunk = "; with --executor warp: worlds per batch (default 1024)" if warp else ""
    p.add_argument("--chunk-size", type=int, help="with --executor ray: experiments per "
                   f"Ray task (default 8){chunk}")  # fmt: skip


def executor_from_args(args: argparse.Namespace, workers: int):  # -> RayExecutor | ... | None
    """The executor `add_executor_args` chose, not started; None for local processes (Ray
    is then neither imported nor started, nor is Warp)."""
    if args.executor == "local":
        if args.address is not None or args.chunk_size is not None:
            raise InputError("--address and --chunk-size need --executor ray or warp")
        return None
    if args.executor == "warp":
        if args.address is not None:
            raise InputError("--address needs --executor ray")
        from transfertwin.study.experiment import WarpExecutor

        worlds = (
            positive_int("--chunk-size", args.chunk_size) if args.chunk_size is not None else 1024
        )
        return WarpExecutor(worlds=worlds)
    from transfertwin.study.experiment import RayExecutor

    chunk = positive_int("--chunk-size", args.chunk_size) if args.chunk_size is not None else 8
    return RayExecutor(args.address, workers=workers, chunk_size=chunk)


def with_executor(command: Callable[[argparse.Namespace], int]):
    """Wrap a command so that the executor of ``--executor`` runs for its whole duration,
    available as ``args.started_executor`` (None for local processes)."""

    @functools.wraps(command)
    def run(args: argparse.Namespace) -> int:
        executor = executor_from_args(args, worker_count(args.workers))
        if executor is None:
            args.started_executor = None
            return command(args)
        with executor:
            args.started_executor = executor
            return command(args)

    return run
