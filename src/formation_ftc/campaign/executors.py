"""Where chunks run: in this process, in a local process pool, or on a Dask cluster.

An executor is a context manager with ``map(fn, plan, chunks)`` yielding ``fn(plan, chunk)`` results
as they finish (any order; the store writes each one atomically), ``describe()`` (one line for the
user) and, optionally, ``prepare(run_steps, n_chunks)``, called with the size of the work before the
context is entered. Every executor calls the same pure
:func:`formation_ftc.campaign.runner.run_chunk`, so the numbers do not depend on the executor.

* :class:`LocalExecutor` -- ``workers=1``: chunks one after the other in this process;
  ``workers=W > 1``: a :class:`concurrent.futures.ProcessPoolExecutor` with the *spawn* start method
  (JAX/XLA is not fork-safe), each worker keeping its compiled programs between chunks;
  ``workers=None`` (the default): one worker per CPU core, at most one per chunk to compute, and
  in-process when the work is small (under :data:`AUTO_POOL_MIN_RUN_STEPS` run-steps, where starting
  worker processes and compiling in each costs more than it saves).
* :class:`DaskExecutor` -- ``scheduler="tcp://HOST:PORT"``: an existing ``dask.distributed`` cluster
  (its workers need formation-ftc installed). Before anything runs, the address gets a bounded
  handshake (TCP connect, then the scheduler's ``identity`` reply, all within ``connect_timeout``,
  default :data:`DEFAULT_CONNECT_TIMEOUT` s, ``--connect-timeout`` or
  ``FORMATION_FTC_DASK_CONNECT_TIMEOUT``), so an address that is not a Dask scheduler (a web server,
  a silent port) is an error naming the address, never a hang. ``n_local=N``: starts a
  ``LocalCluster`` of N single-threaded worker processes.

Workers die with their parent: local pool workers set ``PR_SET_PDEATHSIG`` (Linux) and watch their
parent's PID (:func:`die_with_parent`, the pool's initializer; the league's method pool uses it too),
so a campaign process killed with SIGKILL leaves no worker computing on; the worker processes of a Dask
``LocalCluster`` exit when their nanny's process (the campaign) goes away. :func:`cap_workers` lowers a
requested number of worker processes to the schedulable cores and the available memory, with a warning.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import functools
import logging
import multiprocessing
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit

from formation_ftc.campaign.spec import CampaignError
from formation_ftc.sim.runtime import schedulable_cpus

if TYPE_CHECKING:  # optional dependency (the dask extra)
    from dask.distributed import Client, LocalCluster

__all__ = [
    "LocalExecutor",
    "DaskExecutor",
    "make_executor",
    "parse_scheduler_address",
    "check_reachable",
    "check_scheduler",
    "auto_workers",
    "cap_workers",
    "available_memory",
    "die_with_parent",
    "AUTO_POOL_MIN_RUN_STEPS",
    "DEFAULT_CONNECT_TIMEOUT",
]

#: seconds allowed to reach a Dask scheduler and get its handshake reply
DEFAULT_CONNECT_TIMEOUT = 30.0

#: below this many run-steps (about 10 s of one core for the Li2020 loop) ``workers=None`` stays in-process
AUTO_POOL_MIN_RUN_STEPS = 10_000_000


def auto_workers(run_steps: int, n_chunks: int, cores: int | None = None) -> int:
    """Local workers for ``run_steps`` run-steps in ``n_chunks`` chunks: 1 (in-process) for small work,
    else one per core, at most one per chunk."""
    cores = schedulable_cpus() if cores is None else cores
    if run_steps < AUTO_POOL_MIN_RUN_STEPS:
        return 1
    return max(1, min(cores, n_chunks))


def available_memory() -> int | None:
    """Memory available to new processes [bytes]: ``MemAvailable`` of ``/proc/meminfo`` (Linux), else
    the free physical pages; None when unknown."""
    with (
        contextlib.suppress(OSError, ValueError, IndexError),
        open("/proc/meminfo", encoding="ascii") as f,
    ):
        for line in f:
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return None


def cap_workers(requested: int, *, per_worker_bytes: int, what: str) -> int:
    """``requested`` worker processes, at most one per schedulable CPU core and as many as the available
    memory holds at ``per_worker_bytes`` each (not capped on memory when that is unknown); at least 1.
    Lowering it prints one warning line on stderr naming ``what`` (e.g. ``"--workers"``)."""
    cores = schedulable_cpus()
    memory = available_memory()
    n = max(1, min(requested, cores))
    if memory is not None and per_worker_bytes > 0:
        n = max(1, min(n, memory // per_worker_bytes))
    if n < requested:
        from formation_ftc.limits import format_bytes

        room = ""
        if memory is not None:
            room = (
                f", {format_bytes(memory)} of memory available at about "
                f"{format_bytes(per_worker_bytes)} per worker"
            )
        with contextlib.suppress(OSError, ValueError):  # a closed or full stderr: no warning
            print(
                f"warning: {what}: {requested} worker processes asked for, using {n} ({cores} schedulable CPU "
                f"core(s){room})",
                file=sys.stderr,
            )
    return n


def die_with_parent(parent_pid: int, poll_s: float = 1.0) -> None:
    """Worker initializer: exit when the parent process (``parent_pid``) dies, even by SIGKILL.

    Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``; everywhere: a daemon thread polling ``os.getppid()``
    (a reparented worker has lost its parent) every ``poll_s`` seconds.
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):  # no libc prctl: the watch thread only
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1 = PR_SET_PDEATHSIG
    if os.getppid() != parent_pid:  # the parent died before this line: do not start at all
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(poll_s)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="formation-ftc-parent-watch", daemon=True).start()


def _results(futures: list, as_completed: Callable) -> Iterator:
    """The futures' results as they complete; the others are cancelled when the caller stops."""
    try:
        for f in as_completed(futures):
            yield f.result()
    finally:
        for f in futures:
            f.cancel()


class LocalExecutor:
    """In-process batches (``workers=1``), a spawn-context process pool of ``workers`` processes, or
    ``workers=None``: chosen by :meth:`prepare` from the size of the work (:func:`auto_workers`)."""

    def __init__(self, workers: int | None = None):
        if workers is not None and workers < 1:
            raise CampaignError(f"--workers must be >= 1, got {workers}")
        self.requested = workers
        self.workers = 1 if workers is None else workers
        self._pool: ProcessPoolExecutor | None = None

    def prepare(self, run_steps: int, n_chunks: int) -> None:
        """Size the pool for the work about to be mapped (only when ``workers`` was left to None)."""
        if self.requested is None:
            self.workers = auto_workers(run_steps, n_chunks)

    def __enter__(self) -> LocalExecutor:
        if self.workers > 1:
            self._pool = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=die_with_parent,
                initargs=(os.getpid(),),
            )
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def map(
        self, fn: Callable, plan: Any, chunks: list, start: Callable | None = None
    ) -> Iterator[Any]:
        """Results of ``fn(plan, chunk)`` for every chunk, as they finish.

        In-process with ``start`` (``start(plan, chunk)`` returns the call that finishes the chunk, as
        :func:`formation_ftc.campaign.runner.start_chunk` does): chunk k+1 is started before chunk k is
        finished, so one chunk's Python work overlaps the other's computation; results are the same."""
        if self._pool is not None:
            yield from _results([self._pool.submit(fn, plan, c) for c in chunks], as_completed)
            return
        start = start or (lambda plan, c: functools.partial(fn, plan, c))
        finish: Callable[[], Any] | None = None  # of the chunk started last
        for c in chunks:
            try:
                following = start(plan, c)
            finally:  # on an error too: the chunk already computed is stored before it propagates
                if finish is not None:
                    yield finish()
            finish = following
        if finish is not None:
            yield finish()

    def describe(self) -> str:
        if self.workers == 1:
            return "local (in-process)"
        return f"local process pool ({self.workers} workers)"


def parse_scheduler_address(address: str) -> tuple[str, int]:
    """``tcp://HOST:PORT`` (or ``HOST:PORT``) -> (host, port); clear error otherwise."""
    text = address if "://" in address else f"tcp://{address}"
    parts = urlsplit(text)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "tcp" or not parts.hostname or port is None:
        raise CampaignError(
            f"--scheduler {address!r}: expected tcp://HOST:PORT (e.g. tcp://10.0.0.5:8786)"
        )
    return parts.hostname, port


async def _identity(address: str, timeout: float) -> dict:
    from distributed.comm import connect

    comm = await asyncio.wait_for(connect(address, timeout=timeout), timeout)
    try:
        await asyncio.wait_for(comm.write({"op": "identity"}), timeout)
        return await asyncio.wait_for(comm.read(), timeout)
    finally:
        comm.abort()


def check_scheduler(address: str, timeout: float = DEFAULT_CONNECT_TIMEOUT) -> dict:
    """Bounded Dask handshake: the scheduler's ``identity`` reply within ``timeout`` seconds, else
    :class:`CampaignError` naming the address (also when something else answers on that port)."""
    check_reachable(address, min(timeout, 10.0))
    result: dict[str, Any] = {}

    def target() -> None:
        try:
            result["reply"] = asyncio.run(_identity(address, timeout))
        except BaseException as exc:  # noqa: BLE001 - reported below
            result["error"] = exc

    t = threading.Thread(target=target, name="formation-ftc-dask-probe", daemon=True)
    t.start()
    t.join(timeout + 5.0)  # the probe bounds itself; this join bounds even a stuck event loop
    reply, exc = result.get("reply"), result.get("error")
    if t.is_alive() or isinstance(exc, asyncio.TimeoutError | TimeoutError):
        raise CampaignError(
            f"--scheduler {address}: no Dask scheduler handshake within {timeout:g} s (something "
            f"accepts connections there but does not answer like a Dask scheduler; check the "
            f"address and port, or raise --connect-timeout)"
        )
    if exc is not None:
        raise CampaignError(
            f"--scheduler {address}: not a Dask scheduler, or it refused the handshake "
            f"({type(exc).__name__}: {exc})"
        )
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise CampaignError(f"--scheduler {address}: answered as {kind!r}, not as a Dask scheduler")
    return reply


def check_reachable(address: str, timeout: float = 3.0) -> None:
    """Open (and close) a TCP connection to the scheduler; CampaignError if it cannot be reached."""
    host, port = parse_scheduler_address(address)
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise CampaignError(
            f"cannot reach the Dask scheduler at {address} ({type(exc).__name__}: {exc}; "
            f"checked with a {timeout:g} s timeout before starting any run)"
        ) from None


class DaskExecutor:
    """Chunks as tasks on a Dask cluster (existing scheduler, or a LocalCluster of ``n_local`` workers)."""

    def __init__(
        self,
        scheduler: str | None = None,
        n_local: int | None = None,
        connect_timeout: float | None = None,
    ):
        if (scheduler is None) == (n_local is None):
            raise CampaignError("give exactly one of --scheduler ADDR and --dask-local N")
        if n_local is not None and n_local < 1:
            raise CampaignError(f"--dask-local must be >= 1, got {n_local}")
        if scheduler is not None:
            parse_scheduler_address(scheduler)
        self.scheduler = scheduler
        self.n_local = n_local
        if connect_timeout is None:
            env = os.environ.get("FORMATION_FTC_DASK_CONNECT_TIMEOUT", "").strip()
            try:
                connect_timeout = float(env) if env else DEFAULT_CONNECT_TIMEOUT
            except ValueError:
                raise CampaignError(
                    f"FORMATION_FTC_DASK_CONNECT_TIMEOUT={env!r}: expected seconds"
                ) from None
        if not (connect_timeout > 0 and connect_timeout < 1e6):
            raise CampaignError(f"--connect-timeout must be > 0 s, got {connect_timeout}")
        self.connect_timeout = float(connect_timeout)
        self.client: Client | None = None
        self._cluster: LocalCluster | None = None

    def __enter__(self) -> DaskExecutor:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise CampaignError(
                "Dask executors need the optional dask extra: pip install 'formation-ftc[dask]'"
            ) from None

        if self.scheduler is not None:
            check_scheduler(self.scheduler, self.connect_timeout)
            try:
                self.client = Client(self.scheduler, timeout=f"{self.connect_timeout}s")
            except Exception as exc:  # noqa: BLE001
                raise CampaignError(
                    f"cannot connect to the Dask scheduler at {self.scheduler}: {exc}"
                ) from None
        else:
            self._cluster = LocalCluster(
                n_workers=self.n_local,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                silence_logs=logging.ERROR,
            )
            self.client = Client(self._cluster)
        return self

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            self.client.close()
            self.client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def map(
        self, fn: Callable, plan: Any, chunks: list, start: Callable | None = None
    ) -> Iterator[Any]:
        """Results of ``fn(plan, chunk)`` as the cluster finishes them (``start`` is for in-process
        executors and is not used here: each worker runs whole chunks)."""
        from dask.distributed import as_completed as dask_as_completed

        if not chunks:
            return
        assert self.client is not None, "DaskExecutor.map outside its with block"
        plan_future = self.client.scatter(plan, broadcast=True)
        prefix, pid = f"campaign-{plan.hash[:10]}-chunk", os.getpid()
        futures = [
            self.client.submit(fn, plan_future, c, pure=False, key=f"{prefix}-{c.chunk_id}-{pid}")
            for c in chunks
        ]
        yield from _results(futures, dask_as_completed)

    def describe(self) -> str:
        if self.scheduler:
            return f"dask ({self.scheduler})"
        return f"dask LocalCluster ({self.n_local} workers)"


def make_executor(
    workers: int | None = None,
    scheduler: str | None = None,
    dask_local: int | None = None,
    connect_timeout: float | None = None,
):
    """The executor the command-line options ask for (``workers=None``: automatic local pool)."""
    if scheduler is not None or dask_local is not None:
        if workers is not None:
            raise CampaignError(
                "--workers is for the local executor; with Dask the cluster sets the workers"
            )
        return DaskExecutor(
            scheduler=scheduler, n_local=dask_local, connect_timeout=connect_timeout
        )
    return LocalExecutor(workers)
