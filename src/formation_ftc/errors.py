"""Error classes shared by the command line and the library.

:class:`InputError` is the base of every error caused by what the user gave (a scenario, a campaign,
an expression, an option, an output path, a resource budget): the command line reports it in one line
and exits with status 2. Anything else is unexpected and exits with status 3 (see ``formation-ftc``).
"""

from __future__ import annotations

__all__ = ["InputError", "ResourceLimitError"]


class InputError(ValueError):
    """Bad input: the message names the file or option, the field and what to change."""


class ResourceLimitError(InputError):
    """A scenario or campaign whose estimated memory or run-steps exceed the configured budget."""
