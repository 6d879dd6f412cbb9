"""``formation-ftc check`` without importing JAX (issue 45 item 1): the proxies of
:mod:`formation_ftc._lazy_jax`, and the scenarios whose loop and conditions compute with numpy and scipy
only.

Each case runs in a fresh interpreter (JAX is imported in this one). The scenarios' case runs ``check
--json`` of every built-in scenario and every league method in one process with the proxies and one
without, and compares the documents."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest
import tomli_w

from formation_ftc import _lazy_jax
from formation_ftc.api import list_scenarios
from formation_ftc.league.definition import builtin_leagues, load_league, method_scenario

#: the checks that import JAX, and why: each computes with JAX itself (the rest must not import it)
NEEDS_JAX = {
    "azizi2009-flfr": "the FLFR design's simulated supremum H_i (design/flfr.py, jitted RK4)",
    "li2020-thm2-delays": "the delays' rates by automatic differentiation (delay_statistics)",
    "li2020-thm2-balanced": "the delays' rates by automatic differentiation (delay_statistics)",
    "compose-li2020-delays-on-yang2013": "the delays' rates by automatic differentiation",
    "league:translational:li2020-thm2": "the delays' rates by automatic differentiation",
    "compose-mehrabian-on-attitude-truth": "initial attitude Euler -> quaternion (jitted, JAX's trig)",
    "compose-mehrabian-on-yang2013": "initial attitude Euler -> quaternion (jitted, JAX's trig)",
    "league:attitude:mehrabian": "initial attitude Euler -> quaternion (jitted, JAX's trig)",
    "league:attitude:mehrabian-active": "initial attitude Euler -> quaternion (jitted, JAX's trig)",
    "league:attitude:yang2013": "initial attitude Euler -> quaternion (jitted, JAX's trig)",
    "league:attitude:pd": "initial attitude Euler -> quaternion (jitted, JAX's trig)",
    "yang2013-healthy": "the disturbance expressions sampled with JAX (disturbance_peaks)",
    "yang2013-controller-fault": "the disturbance expressions sampled with JAX (disturbance_peaks)",
}

_CHECKS = """
import contextlib, io, json, sys
targets = json.loads(sys.argv[2])
lazy = sys.argv[1] == "lazy"
from formation_ftc import _lazy_jax
current, first = [None], []
if lazy:
    assert _lazy_jax.install()
    _lazy_jax.call_when_imported(lambda jax: first.append(current[0]))
from formation_ftc.cli import main
out = {}
for name, target in targets:
    current[0] = name
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["check", target, "--json"])
    out[name] = {"code": code, "doc": json.loads(buf.getvalue()), "jax": _lazy_jax.loaded()}
print(json.dumps({"checks": out, "first_jax": first}))
"""


#: the package's own install at import off, so that the scripts install (or not) the proxies themselves
_EAGER_IMPORT = {**os.environ, "FORMATION_FTC_LAZY_JAX": "off"}


def _targets(tmp_path) -> list[tuple[str, str]]:
    """(name, what ``check`` reads) of every built-in scenario and every league method (a file of its
    scenario at the league's first level, no fault): those to stay JAX-free first."""
    out = [(name, name) for name in list_scenarios()]
    for league in builtin_leagues():
        spec = load_league(league)
        for m in spec.methods:
            path = tmp_path / f"{league}-{m.name}.toml"
            path.write_text(tomli_w.dumps(method_scenario(spec, m, spec.levels[0], {})))
            out.append((f"league:{league}:{m.name}", str(path)))
    return sorted(out, key=lambda t: (t[0] in NEEDS_JAX, t[0]))


def test_check_of_every_scenario_with_and_without_jax(tmp_path):
    targets = _targets(tmp_path)
    names = {n for n, _ in targets}
    assert set(NEEDS_JAX) <= names, "stale NEEDS_JAX entries"
    procs = {
        mode: subprocess.Popen(
            [sys.executable, "-c", _CHECKS, mode, json.dumps(targets)],
            env=_EAGER_IMPORT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for mode in ("lazy", "jax")
    }
    results = {}
    for mode, proc in procs.items():
        out, err = proc.communicate(timeout=900)
        assert proc.returncode == 0, err[-3000:]
        results[mode] = json.loads(out.strip().splitlines()[-1])
    lazy, eager = results["lazy"]["checks"], results["jax"]["checks"]
    for name, _ in targets:  # the same documents and exit codes, JAX imported or not
        assert lazy[name]["code"] == eager[name]["code"], name
        assert lazy[name]["doc"] == eager[name]["doc"], name
    assert all(r["jax"] for r in eager.values())  # that process imports JAX at the first build
    free = [n for n, _ in targets if n not in NEEDS_JAX]
    assert "cw-pd-fault" in free
    imported = [n for n in free if lazy[n]["jax"]]
    assert imported == [], f"these checks imported JAX: {imported} ({results['lazy']['first_jax']})"
    # the first one that did is one that computes with JAX (its checks came after the JAX-free ones)
    assert results["lazy"]["first_jax"] == [next(n for n, _ in targets if n in NEEDS_JAX)]


_CLI_PROBE = """
import sys
sys.argv = ["formation-ftc", "check", "cw-pd-fault", "--json"]
from formation_ftc.cli import main
code = main()
from formation_ftc import _lazy_jax
sys.stdout.flush()
print("\\n@@" + repr([_lazy_jax.is_proxy(sys.modules.get("jax")), _lazy_jax.loaded(),
                      sorted(m for m in ("jaxlib", "jax._src") if m in sys.modules), code]))
"""


def test_check_command_imports_no_jax():
    """The process of ``formation-ftc check cw-pd-fault`` (``main()`` without arguments) answers with
    the proxies installed and JAX never imported (issue 45: check <= 0.5 s, ``benchmarks/cli.py``)."""
    out = subprocess.run(
        [sys.executable, "-c", _CLI_PROBE], capture_output=True, text=True, check=True, timeout=600
    )
    *doc, probe = out.stdout.strip().splitlines()
    assert json.loads("\n".join(doc))["all_required_hold"] is True
    assert eval(probe[2:]) == [True, False, [], 0]  # noqa: S307 - our own probe's repr


_PROXY = """
import os, sys, threading
import numpy as np
import formation_ftc
from formation_ftc import _lazy_jax
assert _lazy_jax.install() and not _lazy_jax.install()  # once
import jax
import jax.numpy as jnp
from jax import numpy as jnp2
assert _lazy_jax.is_proxy(jax) and jnp is jnp2 and _lazy_jax.is_proxy(jnp) and jax.numpy is jnp
jax.config.update("jax_numpy_rank_promotion", "raise")  # buffered
assert not isinstance(np.zeros(2), jax.Array) and not issubclass(np.ndarray, jax.Array)
Array = jax.Array  # a reference taken before the import
sys.path.insert(0, sys.argv[1])
import user_module  # does `import jax.numpy as jnp` now
from formation_ftc.sim.components import component, static

@component
class Gain:
    k: object
    n: int = static(default=1)

g = Gain(k=np.array([1.0, 2.0]))
calls = []
_lazy_jax.call_when_imported(calls.append)
assert not _lazy_jax.loaded() and "jaxlib" not in sys.modules and calls == []

# several threads use the proxies at once: one import, every pending registration applied first
results = []
barrier = threading.Barrier(4)
def use():
    barrier.wait()
    results.append(jax.tree_util.tree_leaves(g)[0].tolist())
threads = [threading.Thread(target=use) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
assert results == [[1.0, 2.0]] * 4, results
assert _lazy_jax.loaded() and len(calls) == 1 and not _lazy_jax.is_proxy(calls[0])
real = sys.modules["jax"]
assert not _lazy_jax.is_proxy(real) and real is calls[0]
assert not _lazy_jax.is_proxy(sys.modules["jax.numpy"])
assert jax.config.jax_numpy_rank_promotion == "raise" and jax.config.jax_enable_x64
doubled = jax.tree_util.tree_map(lambda x: 2 * x, g)
assert isinstance(doubled, Gain) and doubled.k.tolist() == [2.0, 4.0]
assert user_module.total(np.arange(4.0)) == 6.0
x = jnp.zeros(3)
assert x.dtype == np.float64 and isinstance(x, Array) and isinstance(x, jax.Array)
assert issubclass(type(x), Array)
assert jax.jit is real.jit and jnp.zeros is sys.modules["jax.numpy"].zeros
assert "Array" in dir(jax) and jax.__doc__ == real.__doc__

@component
class Later:  # decorated after the import: registered at once
    a: object

assert jax.tree_util.tree_leaves(Later(a=np.ones(1)))[0].tolist() == [1.0]
print("ok")
"""

_SUBMODULE = """
import sys
from formation_ftc import _lazy_jax
assert _lazy_jax.install()
import jax
import jax.version  # a submodule under the proxy: imports JAX first (jax/__init__.py), then the module
assert _lazy_jax.loaded() and sys.modules["jax.version"] is sys.modules["jax"].version
import jax.numpy.linalg
import jax.tree_util
from jax.experimental import serialize_executable
real = sys.modules["jax"]
assert _lazy_jax.loaded() and not _lazy_jax.is_proxy(real)
assert sys.modules["jax.numpy.linalg"] is real.numpy.linalg is jax.numpy.linalg
assert sys.modules["jax.tree_util"] is real.tree_util
assert jax.tree_util.__spec__.name == "jax.tree_util" and jax.tree_util.__spec__.origin
assert sys.modules["jax.experimental.serialize_executable"] is serialize_executable
print("ok")
"""


@pytest.mark.parametrize("script", [_PROXY, _SUBMODULE], ids=["proxy", "submodule"])
def test_proxies_import_jax_on_first_use(tmp_path, script):
    (tmp_path / "user_module.py").write_text(
        textwrap.dedent(
            """
            import jax.numpy as jnp

            def total(x):
                return float(jnp.sum(jnp.asarray(x)))
            """
        )
    )
    out = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path)],
        env=_EAGER_IMPORT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() == "ok"


def test_install_is_a_no_op_where_jax_is_imported():
    import jax

    assert not _lazy_jax.install()
    assert sys.modules["jax"] is jax and _lazy_jax.loaded()
    called = []
    _lazy_jax.call_when_imported(called.append)  # at once
    assert called == [jax]


def test_inertial_truth_declares_the_shapes_it_senses():
    """A build reads the inertial truth's sensed shapes without computing its orbits: the same as
    computed."""
    import numpy as np

    from formation_ftc.api import load_scenario
    from formation_ftc.methods.composed import make_loop

    plant = make_loop(load_scenario("compose-li2020-on-orbital-truth")).plant
    state = plant.sensed_state(plant.initial_state())
    assert plant.sensed_shapes() == {k: np.shape(v) for k, v in state.items()} == {"q": (4, 6)}
