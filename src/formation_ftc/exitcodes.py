"""Exit statuses of the command line and the guard that maps exceptions to them.

* 0 -- success; 1 -- a required condition failed or a run diverged (set by the command itself);
* 2 -- bad input (:class:`formation_ftc.errors.InputError`: scenario, campaign, expression, option,
  output path, resource budget): one line ``error: ...`` naming what to change;
* 3 -- an unexpected error (a bug or an environment failure): one line naming the exception and the
  path of a file holding the full traceback (``$FORMATION_FTC_CRASH_DIR``, else
  ``~/.cache/formation_ftc``, else the temporary directory);
* 130 -- interrupted (Ctrl-C).

Writing into a closed pipe (``formation-ftc check --json | head``) ends quietly with status 0.
"""

from __future__ import annotations

import datetime as _dt
import os
import sys
import tempfile
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["EXIT_OK", "EXIT_FAILED", "EXIT_INPUT", "EXIT_UNEXPECTED", "run_guarded", "save_traceback"]

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_UNEXPECTED, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


def _crash_dirs() -> list[Path]:
    dirs = []
    if os.environ.get("FORMATION_FTC_CRASH_DIR"):
        dirs.append(Path(os.environ["FORMATION_FTC_CRASH_DIR"]))
    dirs.append(Path.home() / ".cache" / "formation_ftc")
    dirs.append(Path(tempfile.gettempdir()))
    return dirs


def save_traceback(exc: BaseException) -> Path | None:
    """Write the traceback of ``exc`` to ``crash-<UTC time>-<pid>.txt``; its path, or None if no
    directory was writable."""
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%S.%f")
    text = "".join(traceback.format_exception(exc))
    header = f"formation-ftc crash report\nargv: {sys.argv!r}\npython: {sys.version.split()[0]}\n\n"
    for d in _crash_dirs():
        try:
            d.mkdir(parents=True, exist_ok=True)
            for n in range(100):  # never overwrite an earlier report
                path = d / f"crash-{stamp}-{os.getpid()}{f'-{n}' if n else ''}.txt"
                try:
                    with open(path, "x", encoding="utf-8") as f:
                        f.write(header + text)
                    return path
                except FileExistsError:
                    continue
        except OSError:
            continue
    return None


def _quiet_stdout() -> None:
    """After a broken pipe: point stdout at /dev/null so the interpreter's final flush is silent."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # pragma: no cover - stdout without a file descriptor
        pass


def run_guarded(fn: Callable[[Any], int | None], args: Any, verbose: bool = False) -> int:
    """Call ``fn(args)`` and map every exception to an exit status (see the module docstring);
    ``verbose`` also prints the traceback of a bad-input error."""
    from formation_ftc.errors import InputError

    try:
        code = int(fn(args) or 0)
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        _quiet_stdout()
        return EXIT_OK
    except InputError as exc:
        if verbose:
            traceback.print_exc()
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - the last line of defence: never a raw traceback
        path = save_traceback(exc)
        where = f"traceback saved to {path}" if path else "the traceback could not be saved"
        first = str(exc).splitlines()[0][:300] if str(exc) else ""
        print(f"internal error: {type(exc).__name__}: {first} ({where}; please report it)", file=sys.stderr)
        return EXIT_UNEXPECTED
