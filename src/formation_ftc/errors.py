"""Error classes shared by the command line and the library.

:class:`InputError` is the base of every error caused by what the user gave (a scenario, a campaign,
an expression, an option, an output path, a resource budget): the command line reports it in one line
and exits with status 2. Anything else is unexpected and exits with status 3 (see ``formation-ftc``).
"""

from __future__ import annotations

__all__ = ["InputError", "ResourceLimitError", "MissingExtraError", "require_extra"]


class InputError(ValueError):
    """Bad input: the message names the file or option, the field and what to change."""


class ResourceLimitError(InputError):
    """A scenario or campaign whose estimated memory or run-steps exceed the configured budget."""


class MissingExtraError(InputError):
    """A feature whose optional dependencies (an *extra* of the package) are not installed."""


def require_extra(module: str, extra: str, feature: str):
    """Import ``module`` for ``feature``, or raise :class:`MissingExtraError` (exit status 2) naming the
    ``pip install`` that brings it (``extra`` of ``pyproject.toml``: ``campaign``, ``lmi``, ...)."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtraError(
            f"{feature} needs the optional dependency {module.split('.')[0]!r}, which is not installed: "
            f"run `pip install -e '.[{extra}]'` in your clone of formation-ftc (or `pip install "
            f"'formation-ftc[{extra}]'` from a wheel; docs/install.md)"
        ) from None
