"""Command line interface: `transfertwin` / `python -m transfertwin`.

Thin: one module per command group, each function calling the public API. Logging and
progress drawing are set up here only. Exit codes: 0 success, 2 bad input (one line on
stderr, no partial output files), 1 internal error, 130 interrupted.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

from transfertwin._errors import InputError
from transfertwin.cli import (
    _calibrate,
    _cps,
    _data,
    _dock,
    _docking,
    _perceive,
    _rehearse,
    _replay,
    _study,
    _transfer,
    _validate,
    _web,
)
from transfertwin.cli._common import Parser

__all__ = ["build_parser", "main"]

log = logging.getLogger("transfertwin")

#: What `transfertwin --help` says first: the tool in a sentence.
DESCRIPTION = (
    "transfertwin simulates an object crossing the gap from a transport module (TM) to a "
    "transfer unit (TU), finds the placements that get it across, calibrates the simulation "
    "against real experiments and runs it beside a cyber-physical floor."
)
#: The legend under `transfertwin --help`: the source's notation that help texts cite.
NOTATION = (
    "Notation of the source work (docs/background.md): E^V is a virtual experiment (one "
    "transfer simulated in the twin), E^P a physical one (on the real or emulated plant); "
    "Sec., Eq., Alg. and Fig. numbers are the thesis's."
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = Parser(prog="transfertwin", description=DESCRIPTION, epilog=NOTATION)
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="-v: progress messages (INFO), -vv: debug logging")  # fmt: skip
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    groups = (_transfer, _study, _calibrate, _cps, _docking, _dock, _perceive, _validate)
    for group in (*groups, _rehearse, _data, _web, _replay):
        group.register(sub)
    return parser


def _configure_logging(verbose: int) -> None:
    """stderr: warnings only (-v: INFO, -vv: DEBUG). asyncua's warnings about the demo's
    self-signed loopback certificates and revised session settings are expected, so
    asyncua speaks up on errors only unless -v is given. Commands may add their own
    handlers (e.g. `cps up` logs INFO to cps.log); the stderr handler keeps its level."""
    level = (logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)]
    root = logging.getLogger()
    for old in [h for h in root.handlers if h.get_name() == "transfertwin-cli"]:
        root.removeHandler(old)  # main() called again in one process
    handler = logging.StreamHandler()
    handler.set_name("transfertwin-cli")
    handler.setLevel(level)
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    root.addHandler(handler)
    root.setLevel(level)
    logging.getLogger("asyncua").setLevel(logging.ERROR if verbose == 0 else level)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    try:
        args = build_parser().parse_args(argv)
        _configure_logging(args.verbose)
        return int(args.func(args))
    except InputError as exc:
        print(f"transfertwin: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `transfertwin states | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("transfertwin: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        log.debug("internal error", exc_info=True)
        print(f"transfertwin: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
