"""Progress lines on stderr (rich), one construction for ``campaign run``, ``league run`` (its step
checks included), ``league tune`` and ``reproduce``.

A line is its name (bold), a bar, its count (done/total or percent) and the columns its caller chooses;
clocks show ``h:mm:ss`` (:func:`_clock`). One policy for all: a disabled bar draws nothing, a failing
stderr (closed, full) turns the lines off, and they never stop the work.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

__all__: list[str] = []


def _clock(seconds: float | None) -> str:
    """``h:mm:ss`` of ``seconds`` (whole seconds); ``-:--:--`` when not known."""
    if seconds is None:
        return "-:--:--"
    s = int(seconds)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def _since(started: float | None) -> Callable[[Any], str]:
    """A clock column counting from ``started`` (``time.perf_counter()``; None: now)."""
    t0 = time.perf_counter() if started is None else started
    return lambda task: _clock(time.perf_counter() - t0)


class _Bars:
    """Progress lines on stderr (or ``console``), redrawn by a thread every ``interval`` s (so that the
    clocks move between counts). ``tasks``: name -> the fields of its line's rich task (``total``;
    ``completed`` when it does not start at 0; fields the columns show). After a line's name, bar and
    done/total (``percent``: its percent) come ``columns``: a rich text column (markup, ``{task.*}``
    fields) or a function of the rich task giving its markup at each redraw. Not ``enabled`` (or,
    ``terminal_only``, without a terminal) they draw nothing; a failing stderr turns them off.
    Subclasses update the counts in :meth:`_poll`."""

    def __init__(
        self,
        tasks: Mapping[str, Mapping[str, Any]],
        *columns: str | Callable[[Any], str],
        percent: bool = False,
        enabled: bool = True,
        console: Any = None,
        terminal_only: bool = False,
        interval: float = 0.5,
    ):
        from rich import progress as rp
        from rich.console import Console
        from rich.text import Text

        class Computed(rp.ProgressColumn):
            def __init__(self, markup: Callable[[Any], str]):
                super().__init__()
                self.markup = markup

            def render(self, task: Any) -> Text:
                return Text.from_markup(self.markup(task))

        console = console if console is not None else Console(stderr=True)
        width = max(map(len, tasks), default=0)
        self._progress = rp.Progress(
            rp.TextColumn(f"[bold]{{task.description:<{width}}}"),
            rp.BarColumn(),
            rp.TaskProgressColumn() if percent else rp.MofNCompleteColumn(),
            *(Computed(c) if callable(c) else rp.TextColumn(c) for c in columns),
            console=console,
            auto_refresh=False,
            disable=not (enabled and tasks and (console.is_terminal or not terminal_only)),
        )
        self._ids = {name: self._progress.add_task(name, **t) for name, t in tasks.items()}
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=self._watch, args=(interval,), name="formation-ftc-progress", daemon=True
        )

    def __enter__(self):
        if not self._progress.disable:
            try:
                self._poll()
                self._progress.start()  # draws the first lines
            except (OSError, ValueError):
                self.__exit__()  # off: the work goes on without them
            else:
                self._thread.start()
        return self

    def update_line(self, name: str, **fields: Any) -> None:
        """Set fields of line ``name``'s rich task (``completed``, ``advance``, ``total``, ...)."""
        self._progress.update(self._ids[name], **fields)

    def _poll(self) -> None:
        """Update the counts (called before each redraw)."""

    def _refresh(self) -> None:
        # never concurrent: the first redraw comes before the thread starts, the last after it ends
        self._poll()
        self._progress.refresh()

    def _watch(self, interval: float) -> None:
        # stderr closed or full: no more progress, the work goes on
        with contextlib.suppress(OSError, ValueError):
            while not self._stop.wait(interval):
                self._refresh()

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread.ident is not None:  # started
            self._thread.join()
        if not self._progress.disable:
            with contextlib.suppress(OSError, ValueError):
                self._refresh()
            with contextlib.suppress(OSError, ValueError):
                self._progress.stop()  # restores sys.stdout/sys.stderr even when its last refresh fails
            self._progress.disable = True
