"""Optional dependencies (the ``campaign`` and ``lmi`` extras of pyproject.toml): a feature whose extra
is not installed stops with exit status 2 and names the ``pip install`` to run; the rest of the tool
works without it. Each case runs in a fresh interpreter in which the extra's modules cannot be imported
(``sys.modules[name] = None`` makes ``import name`` raise ImportError, as when it is not installed)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from formation_ftc.errors import InputError, MissingExtraError, require_extra

_WITHOUT = textwrap.dedent("""
    import sys
    for name in sys.argv[1].split(","):
        sys.modules[name] = None
    from formation_ftc.cli import main
    sys.exit(main(sys.argv[2:]))
""")


def _cli_without(modules: str, *argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", _WITHOUT, modules, *argv],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_require_extra_names_the_pip_install():
    assert require_extra("math", "campaign", "x").sqrt(4.0) == 2.0
    with pytest.raises(MissingExtraError, match=r"pip install -e '\.\[lmi\]'") as err:
        require_extra("no_such_module_for_formation_ftc", "lmi", "LMI design")
    assert isinstance(err.value, InputError)  # exit status 2 on the command line


def test_a_campaign_without_the_campaign_extra_exits_2_naming_it(tmp_path):
    proc = _cli_without(
        "pyarrow,pyarrow.parquet",
        "campaign",
        "run",
        "cw-pd-gains",
        "--out",
        str(tmp_path / "c"),
        "--runs",
        "2",
        "--workers",
        "1",
        "--no-progress",
    )
    assert proc.returncode == 2, proc.stderr
    assert "pip install -e '.[campaign]'" in proc.stderr and "pyarrow" in proc.stderr


def test_without_the_extras_a_scenario_still_runs_and_checks(tmp_path):
    proc = _cli_without(
        "pyarrow,pyarrow.parquet,cvxpy",
        "run",
        "cw-pd-fault",
        "--out",
        str(tmp_path / "r"),
        "--set",
        "simulation.horizon=20",  # the 200 steps of the other short cw-pd-fault runs
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "r" / "result.nc").is_file()


def test_an_lmi_design_without_the_lmi_extra_exits_2_naming_it():
    code = textwrap.dedent("""
        import sys
        sys.modules["cvxpy"] = None
        import numpy as np
        from formation_ftc.design.lmi import design_ilo_gains
        from formation_ftc.errors import MissingExtraError
        try:
            design_ilo_gains(-np.eye(2), np.eye(2), np.eye(2))
        except MissingExtraError as exc:
            print(exc)
            sys.exit(2)
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert "pip install -e '.[lmi]'" in proc.stdout and "cvxpy" in proc.stdout
