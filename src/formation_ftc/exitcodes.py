"""Exit statuses of the command line and the guard that maps exceptions to them.

* 0 -- success; 1 -- a required condition failed or a run diverged (set by the command itself), or
  standard output could not be written (a full disk or ``/dev/full``, a closed descriptor ``>&-``):
  one line ``cannot write to standard output: ...``; the result files already written stay;
* 2 -- bad input (:class:`formation_ftc.errors.InputError`: scenario, campaign, expression, option,
  output path, resource budget): one line ``error: ...`` naming what to change;
* 3 -- an unexpected error (a bug or an environment failure): one line naming the exception and the
  path of a file holding the full traceback (``$FORMATION_FTC_CRASH_DIR``, else
  ``~/.cache/formation_ftc``, else the temporary directory); a full disk or quota (``ENOSPC``,
  ``EDQUOT``) is one line ``error: no space left on PATH ...`` and no traceback file (it would need
  the space that is missing);
* 130 -- interrupted (Ctrl-C).

Writing into a pipe whose reader has already exited (``formation-ftc check --json | head``) ends
quietly with status 0: the reader took what it wanted.

Machine-readable output (shared by every command module, which import this module and not each
other): :func:`add_json_option` gives a command ``--json``, :func:`print_json` prints its one JSON
document (typed values: numbers, booleans, null; schemas in docs/cli.md). With ``--json``
(``args.json``), a command that ends with status 2, 3 or 130 also prints ``{"error": MESSAGE,
"exit_code": N}`` on standard output (the message stays on stderr as well), so that a script parsing
stdout sees failures too (:func:`print_json_error`). :func:`lossy_stderr`: a closed or full stderr
never costs a result or changes the exit status.
"""

from __future__ import annotations

import abc
import argparse
import contextlib
import datetime as _dt
import errno
import json
import math
import os
import sys
import tempfile
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from formation_ftc.errors import InputError

__all__ = [
    "EXIT_OK",
    "EXIT_FAILED",
    "EXIT_INPUT",
    "EXIT_UNEXPECTED",
    "run_guarded",
    "save_traceback",
    "add_json_option",
    "jsonable",
    "print_json",
    "print_json_error",
    "lossy_stderr",
]

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_UNEXPECTED, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


def _crash_dirs() -> list[Path]:
    chosen = os.environ.get("FORMATION_FTC_CRASH_DIR")
    return [
        *([Path(chosen)] if chosen else []),
        Path.home() / ".cache" / "formation_ftc",
        Path(tempfile.gettempdir()),
    ]


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
    """After a failed write: point stdout at /dev/null so the interpreter's final flush is silent."""
    with contextlib.suppress(OSError, ValueError, AttributeError):  # stdout without a descriptor
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


class _Wrapped(abc.ABC):
    """A text stream that delegates to ``stream`` what it does not define itself (encoding, fileno,
    buffer, ...; none while ``stream`` is None)."""

    def __init__(self, stream: Any):
        self.stream = stream

    @abc.abstractmethod
    def write(self, text: str) -> int: ...

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)


class _GuardedStdout(_Wrapped):
    """``sys.stdout`` while a command runs: remembers the first write or flush that failed (``failure``)
    and re-raises it, so that :func:`run_guarded` can tell a failure of standard output itself from an
    ``OSError`` of anything else (a result file, a socket). A closed descriptor (``>&-``: Python's
    ``sys.stdout`` is None) fails like one on the first write."""

    failure: OSError | None = None

    def _failed(self, exc: OSError) -> OSError:
        if self.failure is None:
            self.failure = exc
        return exc

    def write(self, text: str) -> int:
        if self.stream is None:
            raise self._failed(OSError(errno.EBADF, "standard output is closed"))
        try:
            return self.stream.write(text)
        except OSError as exc:
            raise self._failed(exc) from None

    def flush(self) -> None:
        if self.stream is None:
            return
        try:
            self.stream.flush()
        except OSError as exc:
            raise self._failed(exc) from None

    def isatty(self) -> bool:
        return False if self.stream is None else bool(self.stream.isatty())


def add_json_option(parser: argparse.ArgumentParser) -> None:
    """``--json`` on a command: one JSON document on stdout instead of the text (docs/cli.md)."""
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON document on stdout (typed values, units in separate keys; "
        'schema in docs/cli.md); errors also as {"error": ..., "exit_code": N}',
    )


def jsonable(obj: Any) -> Any:
    """``obj`` with JSON types only: numpy scalars and arrays as Python numbers, booleans and lists,
    non-finite floats as None (JSON has no NaN or infinity), paths and other objects as strings."""
    if obj is None or isinstance(obj, bool | int | str):
        return obj
    if isinstance(obj, float):  # numpy.float64 too
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [jsonable(v) for v in obj]
    if type(obj).__module__.startswith("numpy") and hasattr(obj, "tolist"):
        return jsonable(obj.tolist())
    return str(obj)


def print_json(doc: Any) -> None:
    """The one JSON document of a ``--json`` command on stdout (through :func:`jsonable`)."""
    print(json.dumps(jsonable(doc), indent=2, allow_nan=False))


def print_json_error(message: str, code: int) -> None:
    """``{"error": message, "exit_code": code}`` on one line of standard output (``--json``); a stdout
    that cannot be written costs the document, never the exit status."""
    with contextlib.suppress(OSError, ValueError, AttributeError):  # full, closed (None), broken
        print(json.dumps({"error": message, "exit_code": code}), flush=True)


def _stdout_message(exc: OSError) -> str:
    reason = exc.strerror or str(exc) or type(exc).__name__
    return f"cannot write to standard output: {reason}"


def run_guarded(fn: Callable[[Any], int | None], args: Any, verbose: bool = False) -> int:
    """Call ``fn(args)`` and map every exception to an exit status (see the module docstring);
    ``verbose`` also prints the traceback of a bad-input error. With ``args.json`` true, an exit
    status 2, 3 or 130 also prints ``{"error": ..., "exit_code": N}`` on standard output."""
    as_json = bool(getattr(args, "json", False))
    original = sys.stdout
    guard = _GuardedStdout(original)
    sys.stdout = guard  # type: ignore[assignment]  # a TextIO by delegation
    try:
        try:
            code = int(fn(args) or 0)
            sys.stdout.flush()
        finally:
            if sys.stdout is guard:  # (a command that replaced stdout restores its own)
                sys.stdout = original
        if guard.failure is not None:  # a write failed and the command went on
            raise guard.failure
        return code
    except OSError as exc:
        # a result file, a socket, a worker's pipe: not standard output
        if exc is not guard.failure:
            if exc.errno in (errno.ENOSPC, errno.EDQUOT):
                return _no_space(exc, as_json)
            return _unexpected(exc, as_json)
        _quiet_stdout()
        if isinstance(exc, BrokenPipeError):  # the reader left (`| head`): it took what it wanted
            return EXIT_OK
        print(_stdout_message(exc), file=sys.stderr)
        return EXIT_FAILED
    except InputError as exc:
        if verbose:
            traceback.print_exc()
        return _failed(str(exc), EXIT_INPUT, as_json, "error: ")
    except KeyboardInterrupt:
        return _failed("interrupted", EXIT_INTERRUPTED, as_json)
    except Exception as exc:  # noqa: BLE001 - the last line of defence: never a raw traceback
        return _unexpected(exc, as_json)


def _no_space(exc: OSError, as_json: bool) -> int:
    """Exit status 3 for a full disk or quota: one line naming the path, no traceback file."""
    where = exc.filename or "the file system being written"
    plain = exc.strerror is None or (
        exc.errno is not None and exc.strerror == os.strerror(exc.errno)
    )
    note = "" if plain else f" ({exc.strerror})"
    message = f"no space left on {where}{note}; free space there or write elsewhere"
    return _failed(message, EXIT_UNEXPECTED, as_json, "error: ")


def _unexpected(exc: Exception, as_json: bool) -> int:
    """Exit status 3: one line naming the exception and where its traceback was saved."""
    path = save_traceback(exc)
    where = f"traceback saved to {path}" if path else "the traceback could not be saved"
    first = str(exc).splitlines()[0][:300] if str(exc) else ""
    message = f"internal error: {type(exc).__name__}: {first} ({where}; please report it)"
    return _failed(message, EXIT_UNEXPECTED, as_json)


def _failed(message: str, code: int, as_json: bool, prefix: str = "") -> int:
    """Exit status ``code``: ``prefix + message`` on stderr (a stderr that cannot be written, e.g. on
    the same full disk, costs the line only), and with ``as_json`` the JSON error document."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        print(prefix + message, file=sys.stderr)
    if as_json:
        print_json_error(message, code)
    return code


class _LossyStream(_Wrapped):
    """``stream`` whose failed writes and flushes are dropped (a closed or full stderr)."""

    def write(self, text: str) -> int:
        try:
            return self.stream.write(text)
        except (OSError, ValueError):
            return len(text)

    def flush(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            self.stream.flush()


@contextlib.contextmanager
def lossy_stderr() -> Iterator[None]:
    """``sys.stderr`` drops what it cannot write while the block runs: warnings, progress bars, log
    lines and error messages never cost a computed result or change the exit status."""
    original = sys.stderr
    sys.stderr = _LossyStream(original)  # type: ignore[assignment]  # a TextIO by delegation
    try:
        yield
    finally:
        sys.stderr = original
