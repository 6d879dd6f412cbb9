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
  (its workers need formation-ftc installed); the address is checked with a short TCP connect before
  anything runs. ``n_local=N``: starts a ``LocalCluster`` of N single-threaded worker processes.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import socket
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any
from urllib.parse import urlsplit

from formation_ftc.campaign.spec import CampaignError

__all__ = ["LocalExecutor", "DaskExecutor", "make_executor", "parse_scheduler_address", "check_reachable",
           "auto_workers", "AUTO_POOL_MIN_RUN_STEPS"]

#: below this many run-steps (about 10 s of one core for the Li2020 loop) ``workers=None`` stays in-process
AUTO_POOL_MIN_RUN_STEPS = 10_000_000


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def auto_workers(run_steps: int, n_chunks: int, cores: int | None = None) -> int:
    """Local workers for ``run_steps`` run-steps in ``n_chunks`` chunks: 1 (in-process) for small work,
    else one per core, at most one per chunk."""
    cores = _cores() if cores is None else cores
    if run_steps < AUTO_POOL_MIN_RUN_STEPS:
        return 1
    return max(1, min(cores, n_chunks))


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
            self._pool = ProcessPoolExecutor(max_workers=self.workers,
                                             mp_context=multiprocessing.get_context("spawn"))
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def map(self, fn: Callable, plan: Any, chunks: list) -> Iterator[Any]:
        if self._pool is None:
            for c in chunks:
                yield fn(plan, c)
            return
        futures = [self._pool.submit(fn, plan, c) for c in chunks]
        try:
            for f in as_completed(futures):
                yield f.result()
        finally:
            for f in futures:
                f.cancel()

    def describe(self) -> str:
        return "local (in-process)" if self.workers == 1 else f"local process pool ({self.workers} workers)"


def parse_scheduler_address(address: str) -> tuple[str, int]:
    """``tcp://HOST:PORT`` (or ``HOST:PORT``) -> (host, port); clear error otherwise."""
    text = address if "://" in address else f"tcp://{address}"
    parts = urlsplit(text)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "tcp" or not parts.hostname or port is None:
        raise CampaignError(f"--scheduler {address!r}: expected tcp://HOST:PORT (e.g. tcp://10.0.0.5:8786)")
    return parts.hostname, port


def check_reachable(address: str, timeout: float = 3.0) -> None:
    """Open (and close) a TCP connection to the scheduler; CampaignError if it cannot be reached."""
    host, port = parse_scheduler_address(address)
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise CampaignError(f"cannot reach the Dask scheduler at {address} ({type(exc).__name__}: {exc}; "
                            f"checked with a {timeout:g} s timeout before starting any run)") from None


class DaskExecutor:
    """Chunks as tasks on a Dask cluster (existing scheduler, or a LocalCluster of ``n_local`` workers)."""

    def __init__(self, scheduler: str | None = None, n_local: int | None = None, connect_timeout: float = 3.0):
        if (scheduler is None) == (n_local is None):
            raise CampaignError("give exactly one of --scheduler ADDR and --dask-local N")
        if n_local is not None and n_local < 1:
            raise CampaignError(f"--dask-local must be >= 1, got {n_local}")
        if scheduler is not None:
            parse_scheduler_address(scheduler)
        self.scheduler = scheduler
        self.n_local = n_local
        self.connect_timeout = connect_timeout
        self.client = None
        self._cluster = None

    def __enter__(self) -> DaskExecutor:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise CampaignError("Dask executors need the optional dask extra: "
                                "pip install 'formation-ftc[dask]'") from None

        if self.scheduler is not None:
            check_reachable(self.scheduler, self.connect_timeout)
            try:
                self.client = Client(self.scheduler, timeout=f"{max(self.connect_timeout, 5.0)}s")
            except Exception as exc:  # noqa: BLE001
                raise CampaignError(f"cannot connect to the Dask scheduler at {self.scheduler}: {exc}") from None
        else:
            self._cluster = LocalCluster(n_workers=self.n_local, threads_per_worker=1, processes=True,
                                         dashboard_address=None, silence_logs=logging.ERROR)
            self.client = Client(self._cluster)
        return self

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            self.client.close()
            self.client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def map(self, fn: Callable, plan: Any, chunks: list) -> Iterator[Any]:
        from dask.distributed import as_completed as dask_as_completed

        if not chunks:
            return
        plan_future = self.client.scatter(plan, broadcast=True)
        futures = [self.client.submit(fn, plan_future, c, pure=False,
                                      key=f"campaign-{plan.hash[:10]}-chunk-{c.chunk_id}-{os.getpid()}")
                   for c in chunks]
        try:
            for f in dask_as_completed(futures):
                yield f.result()
        finally:
            for f in futures:
                f.cancel()

    def describe(self) -> str:
        return f"dask ({self.scheduler})" if self.scheduler else f"dask LocalCluster ({self.n_local} workers)"


def make_executor(workers: int | None = None, scheduler: str | None = None, dask_local: int | None = None):
    """The executor the command-line options ask for (``workers=None``: automatic local pool)."""
    if scheduler is not None or dask_local is not None:
        if workers is not None:
            raise CampaignError("--workers is for the local executor; with Dask the cluster sets the workers")
        return DaskExecutor(scheduler=scheduler, n_local=dask_local)
    return LocalExecutor(workers)
