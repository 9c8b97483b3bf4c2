"""Exceptions shared by every layer.

`InputError` marks bad user input: the CLI turns it into one line on stderr and
exit code 2. Anything else that escapes is an internal error (exit code 1).
"""

from __future__ import annotations

__all__ = ["InputError"]


class InputError(ValueError):
    """Bad input from a user (file, argument, configuration)."""
