"""Where the time of a paper reproduction goes: compile, run, Python post-processing, plotting, report.

``formation-ftc reproduce PAPER --profile`` wraps each paper in a :class:`Profiler`. The phases are
measured as follows (wall-clock seconds, ``time.time``):

compile
    JAX's own monitoring events: tracing to a jaxpr, lowering to MLIR and the XLA backend compile
    (which includes reading the persistent compilation cache). Their time spans are merged (nested
    traces are not counted twice) and taken out of every other phase. This is not "first call minus
    second call": nothing is run twice.
run
    time inside :func:`phase` ``("run")`` blocks (execution of the compiled programs and conversion of
    their outputs to datasets), compile excluded.
plot
    time inside :func:`phase` ``("plot")`` blocks (figures, 3-D trajectory data), compile excluded.
post
    everything else of the paper's wall time: Python post-processing, offline designs, comparison rows.
report
    writing the paper's ``report.json`` / ``summary.json`` (and, as its own row, ``index.html``).

A reproduction marks its blocks with ``with phase("run"): ...``; outside a profiled run
:func:`phase` costs two function calls and records nothing.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

__all__ = ["PHASES", "Profiler", "phase", "active", "format_breakdown"]

#: Phases of the breakdown, in table order.
PHASES = ("compile", "run", "post", "plot", "report")
#: decimals [s] kept in stored phase times: to the microsecond, so that a fast phase is not stored as 0
DIGITS = 6

_COMPILE_EVENTS = frozenset(
    {
        "/jax/core/compile/jaxpr_trace_duration",
        "/jax/core/compile/jaxpr_to_mlir_module_duration",
        "/jax/core/compile/backend_compile_duration",
    }
)

_ACTIVE: Profiler | None = None
_LISTENING = False


def _on_span(event: str, start: float, end: float, **_kwargs) -> None:
    if _ACTIVE is not None and event in _COMPILE_EVENTS:
        _ACTIVE.compile_spans.append((start, end))


def _listen() -> None:
    """Register the JAX time-span listener once per process (JAX offers no way to unregister)."""
    global _LISTENING
    if not _LISTENING:
        import jax.monitoring

        jax.monitoring.register_event_time_span_listener(_on_span)  # type: ignore[arg-type]  # **kwargs typed str|int
        _LISTENING = True


def _merge(spans: list[tuple[float, float]]) -> list[tuple[float, float]]:
    out: list[list[float]] = []
    for a, b in sorted(spans):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def _overlap(a: float, b: float, merged: list[tuple[float, float]]) -> float:
    return sum(max(0.0, min(b, y) - max(a, x)) for x, y in merged)


@dataclass
class Profiler:
    """Phase timer of one paper; use as a context manager around the paper's run.

    Phases nest: an inner :func:`phase` pauses the outer one, so every second is counted once.
    """

    segments: list[tuple[str, float, float]] = field(default_factory=list)
    compile_spans: list[tuple[float, float]] = field(default_factory=list)
    start: float = 0.0
    end: float = 0.0
    _stack: list[list] = field(default_factory=list)
    _previous: Profiler | None = None

    def __enter__(self) -> Profiler:
        global _ACTIVE
        _listen()
        self._previous = _ACTIVE
        _ACTIVE = self
        self.start = time.time()
        return self

    def __exit__(self, *exc) -> None:
        global _ACTIVE
        self.end = time.time()
        while self._stack:  # a phase left open by an exception
            self._close()
        _ACTIVE = self._previous

    def _open(self, name: str) -> None:
        now = time.time()
        if self._stack:  # pause the enclosing phase
            outer = self._stack[-1]
            self.segments.append((outer[0], outer[1], now))
        self._stack.append([name, now])

    def _close(self) -> None:
        now = time.time()
        name, t0 = self._stack.pop()
        self.segments.append((name, t0, now))
        if self._stack:
            self._stack[-1][1] = now  # resume the enclosing phase

    def breakdown(self) -> dict[str, float]:
        """``{phase: seconds}`` for :data:`PHASES` plus ``"total"`` (the profiled wall time); compile is
        the merged JAX compile spans inside the profiled interval."""
        end = self.end or time.time()
        merged = _merge(
            [
                (max(a, self.start), min(b, end))
                for a, b in self.compile_spans
                if b > self.start and a < end
            ]
        )
        compile_s = sum(b - a for a, b in merged)
        out = dict.fromkeys(PHASES, 0.0)
        out["compile"] = compile_s
        inside = 0.0
        for name, a, b in self.segments:
            net = (b - a) - _overlap(a, b, merged)
            out[name] = out.get(name, 0.0) + net
            inside += net
        wall = end - self.start
        out["post"] += max(0.0, wall - compile_s - inside)
        out["total"] = wall
        return {k: round(v, DIGITS) for k, v in out.items()}


def active() -> Profiler | None:
    """The profiler of the paper that is running, or None."""
    return _ACTIVE


@contextmanager
def phase(name: str) -> Iterator[None]:
    """Count the enclosed block as phase ``name`` ("run", "plot", ...) of the active profiler, if any."""
    prof = _ACTIVE
    if prof is None:
        yield
        return
    prof._open(name)
    try:
        yield
    finally:
        prof._close()


def format_breakdown(b: dict[str, float]) -> str:
    """One line, e.g. ``"compile 3.1 s, run 10.2 s, post 0.4 s, plot 2.0 s, report 0.1 s (total 15.8 s)"``."""
    return (
        ", ".join(f"{k} {b.get(k, 0.0):.1f} s" for k in PHASES)
        + f" (total {b.get('total', 0.0):.1f} s)"
    )
