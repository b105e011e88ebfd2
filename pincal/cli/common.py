"""Shared CLI helpers: one-line errors, exit codes."""

from __future__ import annotations

import sys
from functools import wraps

import click

from pincal.errors import PincalError

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2


def fail_cleanly(func):
    """Report PincalError (and file/value errors) as one line on stderr, exit code 1.

    With ``pincal --debug`` the exception propagates with its traceback.
    """

    @wraps(func)
    def wrapper(*args, **kwargs):
        ctx = click.get_current_context()
        try:
            return func(*args, **kwargs)
        except (PincalError, OSError, ValueError) as exc:
            root = ctx.find_root().obj or {}
            if root.get("debug"):
                raise
            click.echo(f"pincal: error: {type(exc).__name__}: {exc}", err=True)
            sys.exit(EXIT_ERROR)

    return wrapper
