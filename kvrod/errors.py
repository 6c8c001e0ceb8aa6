"""The command line's user error (kept apart so that the command modules and ``kvrod.cli``
do not import each other)."""

from __future__ import annotations


class CliError(Exception):
    """A user error: printed as one line, exit code 2."""
