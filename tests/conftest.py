"""Shared test configuration: float64 JAX for every test; the long end-to-end checks start first.

Tests marked ``slow`` (full reproductions, multi-process campaign checks) are moved to the front of
the collection (their relative order kept). Under ``pytest -n 2`` the workers then start on the
longest tests and share the many short ones afterwards, instead of one worker finishing a long test
alone at the end; run serially, the order of the other tests is unchanged.

Memory: every program XLA compiles -- each eager operation on a new shape included -- keeps about
1.4 MB of native heap for as long as JAX's in-memory caches hold it (up to thousands of entries). A
worker that runs hundreds of tests would grow to 3-4 GB that way. After a test that leaves the worker
above :data:`RSS_LIMIT_MB` resident, the caches are dropped (the package's shared programs,
``formation_ftc.sim.programs`` and ``sim.batch``, then ``jax.clear_caches``) and freed memory is
returned to the system (glibc ``malloc_trim``). The programs come back from the persistent compilation
cache, which in the test run keeps every program (``JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0``);
nothing a test asserts depends on which cache served it.
"""

import ctypes
import gc
import os

# every compiled program goes to the persistent cache, however short its compile (the package's
# default keeps programs that compiled for >= 0.2 s): the other xdist worker, and this one after a cache
# clear below, load it instead of compiling it again (measured on tests/components + methods + sim,
# cold cache: 323 -> 288 s wall, 1,348 entries, 17 MB). Set before JAX reads its configuration.
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")

# Under pytest-xdist the workers share the cores: each worker's JAX CPU client gets its share of
# threads (PJRT_NPROC, read when the client starts), as `formation-ftc reproduce` gives its paper
# workers. More threads than cores make XLA hand small operations between threads at a CPU cost
# (benchmarks/cpu_threads.py). The compilation cache is keyed by the thread count (formation_ftc).
_XDIST_WORKERS = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0") or 0)
if _XDIST_WORKERS > 1:
    os.environ.setdefault("PJRT_NPROC", str(max(1, len(os.sched_getaffinity(0)) // _XDIST_WORKERS)))


def _use_package_xla_options() -> None:
    """Give the run's other programs the package's XLA:CPU options, through ``XLA_FLAGS``.

    The package compiles its simulation programs with its own options (:mod:`formation_ftc.sim.runtime.xla`:
    XLA's MLIR fusion emitters and YNNPACK fusions off, per compilation). A test's eager operations and its
    own jitted functions -- thousands of small programs in a run -- get XLA's defaults, where every fusion
    goes through the MLIR pipeline. Here they get the package's options too, process-wide (read when the
    CPU client starts; inherited by the xdist workers and by the processes tests start), once a child
    process has shown that this jaxlib knows them: XLA aborts on an unknown flag. Elementwise functions give
    the same bits with either emitter (tests/sim/runtime/test_xla.py). The package's simulation programs
    (``sim.runtime.xla.jit``, the divergence replay and the build-time attitude conversions included) are
    compiled as without it; the two package functions jitted with JAX's defaults (the FLFR design
    simulation, below ``sim`` in the layers, and tuning's Jacobian) get the options here. Every built-in scenario's metrics and ``reproduce all``'s numbers are
    the same bits with and without the flags (2026-12-06). Fresh-cache ``make test``, back to back on the
    2-core machine: 1,244 -> 1,088 user CPU-s.
    """
    import subprocess
    import sys

    from formation_ftc.sim.runtime.xla import DEFAULT_OPTIONS

    flags = " ".join(
        f"--{name}={str(value).lower() if isinstance(value, bool) else value}"
        for name, value in DEFAULT_OPTIONS.items()
    )
    current = os.environ.get("XLA_FLAGS", "")
    if flags in current or os.environ.get("FORMATION_FTC_TEST_XLA_FLAGS") == "unknown":
        return
    env = {**os.environ, "XLA_FLAGS": f"{current} {flags}".strip()}
    probe = [sys.executable, "-c", "import jax.numpy as jnp; jnp.zeros(2).block_until_ready()"]
    if subprocess.run(probe, env=env, capture_output=True).returncode == 0:
        os.environ["XLA_FLAGS"] = env["XLA_FLAGS"]
    else:  # not this jaxlib's flags: the workers need not probe again
        os.environ["FORMATION_FTC_TEST_XLA_FLAGS"] = "unknown"


_use_package_xla_options()

import jax  # noqa: E402
import jax.monitoring  # noqa: E402
import pytest  # noqa: E402

import formation_ftc  # noqa: E402, F401  (enables jax_enable_x64)
from formation_ftc.sim import runtime  # noqa: E402

# the compilation caches and compiler tuning, as the command line has them (the suite's second worker
# loads what the first compiled); inherited by the processes tests start
runtime.configure()

#: resident memory [MiB] above which a worker drops JAX's compile caches after a test
RSS_LIMIT_MB = int(os.environ.get("FORMATION_FTC_TEST_RSS_LIMIT_MB", "1200"))


def _resident_mb() -> int | None:
    """Current resident set size of this process [MiB] (Linux /proc), None elsewhere."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) // 1024
    except OSError:
        return None
    return None


def _malloc_trim() -> None:
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc
        pass


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item, nextitem):
    """After the test's fixtures are finalised: drop the compile caches above :data:`RSS_LIMIT_MB`."""
    rss = _resident_mb()
    if rss is not None and rss > RSS_LIMIT_MB:
        from formation_ftc.sim import batch, programs

        programs.clear()  # the process's shared programs and executables, outside JAX's caches
        batch.clear()
        jax.clear_caches()
        gc.collect()
        _malloc_trim()


#: names JAX gives a compiled closed-loop run (``sim.programs``' shared ``_run``, a test's own ``run``)
RUN_NAMES = ("jit(run)", "jit(_run)")
#: compile events of a closed-loop ``run`` program (JAX's ``jax.monitoring``), for :func:`run_compiles`
_RUN_COMPILES: list[str] = []


def _count_run_compiles(event: str, duration: float, **kw) -> None:
    if event == "/jax/core/compile/backend_compile_duration" and kw.get("fun_name") in RUN_NAMES:
        _RUN_COMPILES.append(event)


jax.monitoring.register_event_duration_secs_listener(_count_run_compiles)


@pytest.fixture
def run_compiles() -> list[str]:
    """XLA compiles (persistent-cache loads included) of a closed-loop ``run`` program from here on."""
    _RUN_COMPILES.clear()
    return _RUN_COMPILES


@pytest.fixture(scope="module")
def cw_gain_pair():
    """Two cw-pd-fault scenarios of one structure (20 s) that differ only in the gain ``controller.kp``."""
    from formation_ftc.api import load_scenario

    return [
        load_scenario("cw-pd-fault", {"simulation.horizon": 20.0, "controller.kp": kp})
        for kp in (2.0, 3.0)
    ]


def pytest_collection_modifyitems(session, config, items):
    """Stable partition: ``slow``-marked tests first (same order on every xdist worker)."""
    slow = [it for it in items if it.get_closest_marker("slow") is not None]
    if slow and config.getoption("numprocesses", default=None):
        rest = [it for it in items if it.get_closest_marker("slow") is None]
        items[:] = slow + rest
