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
from transfertwin.cli import _calibrate, _cps, _data, _docking, _study, _transfer, _validate
from transfertwin.cli._common import Parser

__all__ = ["build_parser", "main"]

log = logging.getLogger("transfertwin")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = Parser(prog="transfertwin", description=__doc__.splitlines()[0])
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for group in (_transfer, _study, _calibrate, _cps, _docking, _validate, _data):
        group.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    try:
        args = build_parser().parse_args(argv)
        logging.basicConfig(
            level=logging.DEBUG if args.verbose else logging.WARNING,
            format="%(levelname)s %(name)s: %(message)s",
        )
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
