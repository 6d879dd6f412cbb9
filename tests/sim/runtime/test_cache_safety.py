"""JAX's persistent compilation cache is used only while no one else can write or swap it
(:func:`formation_ftc.sim.runtime.unsafe_directory`, checked by ``configure`` and before every
compilation that reads the cache).

The end-to-end cases run fresh interpreters (JAX opens its cache once per process) and compile only
one-operation programs, except one ``formation-ftc run`` of a 100 s free drift. The attack they play:
after start-up, the cache directory is swapped for one that holds another program's executable under
the victim program's cache key. Where no one else could have done that (a private path) the swap takes
effect -- the test's control, showing the poisoning is real -- and where an ancestor is writable by a
group or owned by another uid, the process computes its own numbers and says so in one line."""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from formation_ftc.sim import runtime
from formation_ftc.sim.runtime import private_cache_dir, unsafe_directory

ROOT_ONLY = pytest.mark.skipif(
    os.geteuid() != 0, reason="needs root: os.chown to another uid, a root-owned sticky directory"
)
OTHER_UID = 12345


@pytest.fixture
def base(tmp_path) -> Path:
    """A private directory whose every ancestor passes the check (else the test cannot say anything)."""
    real = Path(os.path.realpath(tmp_path))
    problem = unsafe_directory(real)
    if problem is not None:
        pytest.skip(f"the temporary directory itself is refused: {problem}")
    return real


def _chain(base: Path) -> list[Path]:
    """base/a/b/cache, every level mode 0700."""
    levels = [base / "a", base / "a" / "b", base / "a" / "b" / "cache"]
    for d in levels:
        d.mkdir(mode=0o700)
    return levels


@pytest.mark.parametrize("level", [0, 1, 2])
def test_a_group_or_world_writable_directory_at_any_level_is_refused(base, level):
    levels = _chain(base)
    cache = levels[-1]
    assert unsafe_directory(cache) is None
    for bits in (stat.S_IWGRP, stat.S_IWOTH):
        os.chmod(levels[level], 0o700 | bits)
        assert unsafe_directory(cache) == f"{levels[level]} is writable by its group or by others"
        os.chmod(levels[level], 0o700)
    assert unsafe_directory(cache) is None


@ROOT_ONLY
@pytest.mark.parametrize("level", [0, 1, 2])
def test_a_directory_owned_by_another_uid_at_any_level_is_refused(base, level):
    levels = _chain(base)
    os.chown(levels[level], OTHER_UID, -1)
    try:
        assert unsafe_directory(levels[-1]) == (
            f"{levels[level]} is owned by uid {OTHER_UID}, neither by you nor by root"
        )
    finally:
        os.chown(levels[level], os.geteuid(), -1)
    assert unsafe_directory(levels[-1]) is None


def test_a_symbolic_link_on_the_path_is_refused_and_a_linked_home_is_resolved_once(base):
    real_home = base / "data" / "you"
    real_home.mkdir(parents=True, mode=0o700)
    (base / "home").mkdir(mode=0o700)
    link = base / "home" / "you"
    link.symlink_to(real_home)
    assert unsafe_directory(link) == f"{link} is a symbolic link"
    # configure() resolves the path once, creates what is missing privately and hands JAX the real path
    got = private_cache_dir(str(link / ".cache" / "jax"))
    assert got == str(real_home / ".cache" / "jax")
    assert stat.S_IMODE(os.stat(got).st_mode) == 0o700


def test_a_sticky_directory_counts_only_as_root_owned_ancestor_of_a_private_directory(base):
    sticky = base / "sticky"
    sticky.mkdir()
    os.chmod(sticky, 0o1777)
    mine = sticky / "mine"
    mine.mkdir(mode=0o700)
    if os.geteuid() != 0:  # sticky, but owned by a user who is not root: anyone may write there
        assert unsafe_directory(mine) == f"{sticky} is writable by its group or by others"
        return
    assert unsafe_directory(mine) is None  # /tmp/you-cache
    assert (
        unsafe_directory(sticky) == f"{sticky} is writable by its group or by others"
    )  # not as the cache
    os.chmod(mine, 0o770)
    assert unsafe_directory(mine) == f"{mine} is writable by its group or by others"
    os.chmod(mine, 0o700)
    os.chown(mine, OTHER_UID, -1)  # another user made it first
    assert (
        unsafe_directory(mine) == f"{mine} is owned by uid {OTHER_UID}, neither by you nor by root"
    )
    os.chown(mine, 0, -1)
    os.chmod(sticky, 0o777)  # world-writable without the sticky bit: anyone may swap "mine"
    assert unsafe_directory(mine) == f"{sticky} is writable by its group or by others"


def test_a_new_cache_directory_is_created_in_a_root_owned_sticky_directory(base, capsys):
    """FORMATION_FTC_JAX_CACHE=/tmp/my-cache when /tmp/my-cache does not exist yet: the cache is made
    there (mode 0700) and used; a sticky directory that is not root's stays refused."""
    sticky = base / "sticky"
    sticky.mkdir()
    os.chmod(sticky, 0o1777)
    got = private_cache_dir(str(sticky / "my-cache" / "jax"))
    if os.geteuid() != 0:  # sticky, but owned by a user who is not root: nothing is created
        assert got is None and not any(sticky.iterdir())
        assert f"{sticky} is writable by its group or by others" in capsys.readouterr().err
        return
    assert got == str(sticky / "my-cache" / "jax")
    assert [stat.S_IMODE(os.stat(d).st_mode) for d in (sticky / "my-cache", got)] == [0o700, 0o700]
    assert capsys.readouterr().err == ""
    assert private_cache_dir(str(sticky)) is None  # the sticky directory itself is not a cache


def test_nothing_is_created_under_a_refused_directory(base, capsys):
    shared = base / "shared"
    shared.mkdir(mode=0o775)
    os.chmod(shared, 0o775)
    assert private_cache_dir(str(shared / "formation_ftc" / "jax")) is None
    assert not any(shared.iterdir())
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{shared} is writable by its group or by others" in err[0]
    assert f"chmod go-w {shared}" in err[0] and "FORMATION_FTC_JAX_CACHE" in err[0]


def _env(**extra: str) -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if k
        not in (
            "JAX_COMPILATION_CACHE_DIR",
            "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS",
            "FORMATION_FTC_JAX_CACHE",
            runtime.ENV_SWITCH,
        )
    }
    env["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = (
        "0"  # the one-operation programs are kept too
    )
    env.update(extra)
    return env


def _python(script: str, *args: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [sys.executable, "-c", script, *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=180,
    )
    assert proc.returncode == 0, proc.stderr
    return proc


_UMASK = """
import json, os, sys
os.umask(0o002)
import numpy as np
from formation_ftc.sim import runtime
cache = runtime.configure()
import jax, jax.monitoring
hits = []
jax.monitoring.register_event_listener(
    lambda e, **k: hits.append(e) if e == "/jax/compilation_cache/cache_hits" else None)
from formation_ftc.sim.runtime import xla
def umask_probe(x):
    return x * 3.0 + 1.0
xla.jit(umask_probe)(np.arange(3.0))
print(json.dumps({"cache": cache, "hits": len(hits)}))
"""


def test_default_directories_are_created_private_under_umask_002_and_used(base):
    home = base / "home"
    home.mkdir(mode=0o755)
    env = _env(HOME=str(home))
    first = _python(_UMASK, env=env)
    got = json.loads(first.stdout.strip().splitlines()[-1])
    made = [".cache", ".cache/formation_ftc", ".cache/formation_ftc/jax"]
    made.append(f".cache/formation_ftc/jax/cpu-threads-{runtime.cpu_threads()}")
    assert got["cache"] == str(home / made[-1])
    assert {d: oct(stat.S_IMODE(os.stat(home / d).st_mode)) for d in made} == dict.fromkeys(
        made, "0o700"
    )
    assert "compilation cache off" not in first.stderr
    assert any(p.name.startswith("jit_umask_probe-") for p in Path(got["cache"]).iterdir())
    # the next process is not refused: it finds the program the first one stored
    second = _python(_UMASK, env=env)
    again = json.loads(second.stdout.strip().splitlines()[-1])
    assert again["cache"] == got["cache"] and again["hits"] >= 1
    assert "compilation cache off" not in second.stderr


_ATTACK = """
import json, os, shutil, sys
import numpy as np
action, poison = sys.argv[1], sys.argv[2]
from formation_ftc.sim import runtime
cache = runtime.configure()
import jax, jax.monitoring
hits = []
jax.monitoring.register_event_listener(
    lambda e, **k: hits.append(e) if e == "/jax/compilation_cache/cache_hits" else None)
from formation_ftc.sim.runtime import xla
def victim(x):
    return x + 1.0
def intruder(x):
    return 2.0 * x + 100.0
x = np.arange(4.0)
if action == "prepare":  # store both programs; print their entry files
    xla.jit(victim)(x), xla.jit(intruder)(x)
    print(json.dumps({n: [os.path.join(cache, p) for p in os.listdir(cache) if p.startswith(f"jit_{n}-")]
                      for n in ("victim", "intruder")}))
    sys.exit()
program = xla.jit(victim)  # made (and the cache checked) while the path is still private
anc = os.path.dirname(os.path.dirname(cache))
if action == "group-writable":
    os.chmod(anc, 0o770)
elif action == "foreign-owned":
    os.chown(anc, 12345, -1)
# the swap: a fresh directory whose entry under the victim's key is the intruder's executable
os.rename(cache, cache + ".old")
os.mkdir(cache, 0o700)
name, data = poison.split("=", 1)
shutil.copyfile(data, os.path.join(cache, name))
print(json.dumps({"result": np.asarray(program(x)).tolist(), "hits": len(hits)}))
"""


@pytest.fixture(scope="module")
def swap_site(tmp_path_factory) -> tuple[Path, str]:
    """A cache path ``ROOT/anc/cache`` and the poison for it: ``VICTIM_ENTRY=INTRUDER_FILE``, the
    entry name of ``victim`` and a copy of ``intruder``'s stored executable. JAX's cache key includes
    the cache directory's path (an XLA option names a directory inside it), so the entries are made
    under the path the attacked processes use."""
    root = Path(os.path.realpath(tmp_path_factory.mktemp("swap")))
    if unsafe_directory(root) is not None:
        pytest.skip(f"the temporary directory itself is refused: {unsafe_directory(root)}")
    cache = root / "anc" / "cache"
    proc = _python(_ATTACK, "prepare", "-", env=_env(FORMATION_FTC_JAX_CACHE=str(cache)))
    files = json.loads(proc.stdout.strip().splitlines()[-1])
    assert len(files["victim"]) == 1 and len(files["intruder"]) == 1, files
    intruder = shutil.copyfile(files["intruder"][0], root / "intruder-entry")
    shutil.rmtree(root / "anc")
    return cache, f"{Path(files['victim'][0]).name}={intruder}"


@pytest.mark.parametrize(
    "action, own_numbers",
    [
        ("none", False),  # private path: the swap takes effect (what would make the attack real)
        ("group-writable", True),
        pytest.param("foreign-owned", True, marks=ROOT_ONLY),
    ],
)
def test_a_cache_swapped_after_start_up_is_not_read_once_the_path_is_not_private(
    swap_site, action, own_numbers
):
    cache, poison = swap_site
    try:
        proc = _python(_ATTACK, action, poison, env=_env(FORMATION_FTC_JAX_CACHE=str(cache)))
    finally:
        shutil.rmtree(cache.parent, ignore_errors=True)
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    x = np.arange(4.0)
    if own_numbers:
        assert got["result"] == (x + 1.0).tolist() and got["hits"] == 0
        lines = [ln for ln in proc.stderr.splitlines() if "compilation cache off" in ln]
        assert len(lines) == 1 and f"{cache.parent} is " in lines[0], proc.stderr
    else:
        assert got["result"] == (2.0 * x + 100.0).tolist() and got["hits"] == 1
        assert "compilation cache off" not in proc.stderr


_SETTINGS = """
import json, os, sys
import numpy as np
from formation_ftc.sim import runtime
cache = runtime.configure()
import jax, jax.monitoring
hits = []
jax.monitoring.register_event_listener(
    lambda e, **k: hits.append(e) if e == "/jax/compilation_cache/cache_hits" else None)
def probe(x):
    return 5.0 * x - 1.0
x = np.arange(3.0)
stored = lambda: len([p for p in os.listdir(cache) if p.startswith("jit_probe-")])
def compile_afresh():
    jax.clear_caches()  # JAX's in-memory caches: the next call compiles, or loads from the cache
    n = len(hits)
    jax.jit(probe)(x)
    return len(hits) - n
jax.jit(lambda v: v + 1.0)(x)  # the cache is opened
jax.config.update("jax_compilation_cache_dir", None)
jax.config.update("jax_enable_compilation_cache", False)
out = {"settings": [compile_afresh(), stored(), compile_afresh()]}  # written, then read back
os.chmod(os.path.dirname(os.path.dirname(cache)), 0o770)
out["refused"] = not runtime.check_cache()  # switches the cache off
os.chmod(os.path.dirname(os.path.dirname(cache)), 0o700)
for p in os.listdir(cache):
    if p.startswith("jit_probe-"):
        os.remove(os.path.join(cache, p))
out["off"] = [compile_afresh(), stored(), compile_afresh(), stored()]
print(json.dumps(out))
"""


def test_jax_reads_an_opened_cache_whatever_its_settings_until_the_runtime_resets_it(base):
    """jax 0.10.2 opens its cache once; ``jax_compilation_cache_dir = None`` and
    ``jax_enable_compilation_cache = False`` after that neither stop it writing nor reading there.
    The runtime's switch-off (what a failed check does) resets the opened cache as well."""
    proc = _python(_SETTINGS, env=_env(FORMATION_FTC_JAX_CACHE=str(base / "anc" / "cache")))
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    # first compile: 0 hits, stored (1 entry); second: read back from the "disabled" cache (1 hit)
    assert got["settings"] == [0, 1, 1]
    assert got["refused"] is True
    assert got["off"] == [0, 0, 0, 0]  # neither read nor written
    lines = [ln for ln in proc.stderr.splitlines() if "compilation cache off" in ln]
    assert len(lines) == 1 and f"{base / 'anc'} is writable by its group" in lines[0]


def test_run_with_a_cache_under_a_group_writable_directory_gives_the_scenarios_own_numbers(base):
    from formation_ftc.api import load_scenario, simulate_with_metrics

    shared = base / "shared"
    shared.mkdir()
    os.chmod(shared, 0o775)
    out = base / "out"
    env = _env(FORMATION_FTC_JAX_CACHE=str(shared / "jax"))
    cli = [sys.executable, "-m", "formation_ftc", "run", "cw-free-drift", "--out", str(out)]
    proc = subprocess.run(
        [*cli, "--set", "simulation.horizon=100"],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if "compilation cache off" in ln]
    assert len(lines) == 1 and f"{shared} is writable by its group or by others" in lines[0]
    assert not any(shared.iterdir())  # not used: nothing created or stored there
    written = json.loads((out / "metrics.json").read_text())
    _, metrics = simulate_with_metrics(
        load_scenario("cw-free-drift", {"simulation.horizon": 100.0})
    )
    assert metrics and {k: written[k] for k in metrics} == {k: float(v) for k, v in metrics.items()}
    shutil.rmtree(out)
