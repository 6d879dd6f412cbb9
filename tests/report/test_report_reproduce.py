"""Orchestration of ``formation-ftc reproduce`` with fake reproductions (no simulation).

Truths: the files the fakes write, the fakes' own reports (counted by hand), the documented JSON
layout, and the refusal rules of issue 9 ("an output directory that exists and is not a previous
report is refused unless --force; a paper name that does not exist lists the valid ones").
"""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import sys
import time

import numpy as np
import pytest
from report_fakes import failing_reproduction, ok_reproduction, wrong_type_reproduction
from rich.console import Console

from formation_ftc import registry
from formation_ftc.registry import PaperReport, Reproduction
from formation_ftc.report import reproduce as rp


def _console() -> Console:
    return Console(file=io.StringIO(), width=140)


def _run(papers, out, available, **kw):
    console = _console()
    result = rp.reproduce(
        papers, out, available=available, progress=kw.pop("progress", False), console=console, **kw
    )
    return result, console.file.getvalue()


def _read(path):
    # strict JSON: the standard parser must accept it with NaN/Infinity rejected
    return json.loads(
        path.read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON constant {c}")
    )


def test_all_papers_files_and_summary_layout(tmp_path):
    calls = []
    avail = {
        "alpha": ok_reproduction("alpha", calls=calls),
        "beta": ok_reproduction("beta", calls=calls),
    }
    out = tmp_path / "rep"
    result, text = _run(["all"], out, avail)
    assert result["exit_code"] == 0
    assert [c[0] for c in calls] == ["alpha", "beta"]  # registry order kept
    assert [c[1] for c in calls] == [out / "alpha", out / "beta"]
    assert (out / rp.MARKER_NAME).is_file()
    for name in (
        "index.html",
        "summary.json",
        "alpha/report.json",
        "alpha/summary.json",
        "alpha/fig3.png",
        "beta/fig4.png",
    ):
        assert (out / name).is_file(), name

    summary = _read(out / "summary.json")
    assert set(summary) == {"alpha", "beta", "metadata"}
    assert summary["alpha"]["tracking_error_m"] == 0.0125
    assert summary["alpha"]["series"] == [0, 1, 2]
    assert summary["alpha"]["undefined"] == "nan"  # non-finite float -> string (strict JSON)
    meta = summary["metadata"]
    assert meta["papers"] == ["alpha", "beta"]
    assert meta["status"] == {"alpha": "ok", "beta": "ok"}
    assert meta["seeds"] == {"alpha": [7, 8], "beta": [7, 8]}
    assert "git_commit" in meta and "version_jax" in meta

    report = _read(out / "alpha" / "report.json")
    assert (
        report["schema"] == rp.REPORT_SCHEMA
        and report["status"] == "ok"
        and report["error"] is None
    )
    assert report["verdicts"] == {"match": 1, "differs": 1, "not stated": 1}
    assert report["checks_summary"] == {
        "hold": 1,
        "fail": 1,
        "unproven": 0,
        "not evaluated": 1,
        "required_failed": 1,
    }
    assert [f["number"] for f in report["figures"]] == ["3", "4"] and all(
        f["exists"] for f in report["figures"]
    )
    assert report["seeds"] == [7, 8] and report["notes"] == ["alpha note"]
    assert report["errata"] == [{"id": "E001-01", "text": "alpha: sign of eq. (7) corrected"}]
    assert report["wall_time_s"] >= 0.0
    paper_summary = _read(out / "beta" / "summary.json")
    assert paper_summary["paper"] == "beta" and paper_summary["settled"] is True
    # the wall-time table is printed at the end
    assert "wall time" in text and "alpha" in text and "beta" in text and "total" in text


def test_single_paper_summary_is_top_level(tmp_path):
    avail = {"alpha": ok_reproduction("alpha"), "beta": ok_reproduction("beta")}
    result, _ = _run(["beta"], tmp_path / "one", avail)
    summary = _read(tmp_path / "one" / "summary.json")
    assert (
        summary["paper"] == "beta"
        and summary["tracking_error_m"] == 0.0125
        and "metadata" in summary
    )
    assert "alpha" not in summary and not (tmp_path / "one" / "alpha").exists()
    assert result["summary"] == summary


def test_wall_time_is_measured_around_the_run(tmp_path):
    base = ok_reproduction("slow")

    def slow_run(out_dir, progress):
        time.sleep(0.2)
        return base.run(out_dir, progress)

    avail = {"slow": Reproduction("slow", "Slow", "", "", [], slow_run)}
    result, _ = _run(["slow"], tmp_path / "w", avail)
    # a lower bound only (sleep guarantees it); no upper/timing threshold
    assert result["papers"]["slow"]["wall_time_s"] >= 0.2
    assert _read(tmp_path / "w" / "slow" / "report.json")["wall_time_s"] >= 0.2


def test_failing_paper_is_recorded_and_others_still_run(tmp_path):
    avail = {
        "alpha": ok_reproduction("alpha"),
        "broken": failing_reproduction("broken", "solver exploded"),
        "gamma": ok_reproduction("gamma"),
        "wrongtype": wrong_type_reproduction(),
    }
    out = tmp_path / "f"
    result, text = _run(["all"], out, avail)
    assert result["exit_code"] == 1
    status = {p: v["status"] for p, v in result["papers"].items()}
    assert status == {"alpha": "ok", "broken": "failed", "gamma": "ok", "wrongtype": "failed"}
    broken = _read(out / "broken" / "report.json")
    assert "Traceback" in broken["error"] and "RuntimeError: solver exploded" in broken["error"]
    assert _read(out / "broken" / "summary.json") == {
        "status": "failed",
        "error": "RuntimeError: solver exploded",
        "paper": "broken",
    }
    assert "PaperReport" in _read(out / "wrongtype" / "report.json")["error"]
    summary = _read(out / "summary.json")
    assert summary["broken"]["status"] == "failed" and summary["gamma"]["settled"] is True
    page = (out / "index.html").read_text()
    assert "solver exploded" in page and 'data-status="failed"' in page
    assert "broken failed" in text and "FAILED" in text


def test_missing_figure_is_a_warning_not_a_crash(tmp_path):
    def run(out_dir, progress):
        rep = ok_reproduction("alpha").run(out_dir, progress)
        (out_dir / "fig4.png").unlink()
        return rep

    avail = {"alpha": Reproduction("alpha", "A", "", "", [], run)}
    result, _ = _run(["alpha"], tmp_path / "m", avail)
    report = _read(tmp_path / "m" / "alpha" / "report.json")
    assert result["exit_code"] == 0
    assert [f["exists"] for f in report["figures"]] == [True, False]
    assert report["warnings"] == ["figure 4: file fig4.png was not written"]


def test_progress_bar_callback_tolerates_odd_values(tmp_path):
    def run(out_dir, progress):
        for value in (-1.0, 0.5, 7.0, float("nan"), None, "x"):
            progress(value, "step")
        progress(1.0, "")
        return PaperReport("p", {"ok": 1})

    console = Console(file=io.StringIO(), width=100, force_terminal=False)
    bar = rp._Bar(True, 1, console=console)
    with bar:
        cb = bar.callback(0, "p")
        cb(2.0, "too far")
        assert bar._progress.tasks[0].completed == 1.0  # clamped to this paper's share
        cb(float("nan"), "nan")
        assert bar._progress.tasks[0].completed == 0.0
    result, _ = _run(
        ["p"], tmp_path / "pb", {"p": Reproduction("p", "P", "", "", [], run)}, progress=True
    )
    assert result["exit_code"] == 0


# ------------------------------------------------------------------------------------ bad input
def test_unknown_paper_lists_valid_ones(tmp_path):
    avail = {"alpha": ok_reproduction("alpha"), "beta": ok_reproduction("beta")}
    with pytest.raises(rp.ReproduceError) as err:
        _run(["gamma"], tmp_path / "u", avail)
    assert "unknown paper 'gamma'" in str(err.value) and "valid: alpha, beta, all" in str(err.value)
    assert not (tmp_path / "u").exists()  # nothing written before the name is validated


def test_select_papers_order_and_dedup():
    assert rp.select_papers(["b", "a", "b"], ["a", "b", "c"]) == ["a", "b"]
    assert rp.select_papers(["all"], ["a", "b"]) == ["a", "b"]
    with pytest.raises(rp.ReproduceError, match="no paper given"):
        rp.select_papers([], ["a"])
    with pytest.raises(rp.ReproduceError, match="no paper reproduction is registered"):
        rp.select_papers(["all"], [])


def test_nonempty_foreign_directory_refused_unless_force(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    avail = {"alpha": ok_reproduction("alpha")}
    with pytest.raises(rp.ReproduceError, match="not a previous formation-ftc report.*--force"):
        _run(["alpha"], out, avail)
    assert sorted(p.name for p in out.iterdir()) == ["thesis.tex"]  # untouched
    result, _ = _run(["alpha"], out, avail, force=True)
    assert result["exit_code"] == 0 and (out / "thesis.tex").read_text() == "precious"
    assert (out / rp.MARKER_NAME).is_file()


def test_empty_directory_and_file_target(tmp_path):
    (tmp_path / "empty").mkdir()
    assert rp.prepare_output(tmp_path / "empty") is False
    (tmp_path / "afile").write_text("x")
    with pytest.raises(rp.ReproduceError, match="not a directory"):
        rp.prepare_output(tmp_path / "afile", force=True)


def test_previous_report_is_overwritten_and_stale_figures_removed(tmp_path):
    out = tmp_path / "again"
    _run(["alpha"], out, {"alpha": ok_reproduction("alpha", figure_sizes=((8, 8), (8, 8), (8, 8)))})
    assert (out / "alpha" / "fig5.png").is_file()
    result, _ = _run(["alpha"], out, {"alpha": ok_reproduction("alpha", figure_sizes=((8, 8),))})
    assert result["exit_code"] == 0
    assert sorted(p.name for p in (out / "alpha").glob("*.png")) == ["fig3.png"]


# --------------------------------------------------------------------------------------- JSON
def test_to_jsonable_conversions():
    import jax.numpy as jnp

    data = {
        1: np.float32(0.5),
        "a": jnp.array([1.0, 2.0]),
        "b": (np.int64(3), {np.inf, -np.inf}),
        "c": float("-inf"),
        "d": np.array([[1, 2]]),
        "e": np.bool_(True),
        "f": 1 + 2j,
        "g": None,
    }
    out = rp.to_jsonable(data)
    assert out == {
        "1": 0.5,
        "a": [1.0, 2.0],
        "b": [3, ["-inf", "inf"]],
        "c": "-inf",
        "d": [[1, 2]],
        "e": True,
        "f": "(1+2j)",
        "g": None,
    }
    json.dumps(out, allow_nan=False)
    assert math.isclose(rp.to_jsonable(jnp.float64(0.1)), 0.1)


# ---------------------------------------------------------------------------------------- CLI
def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="formation-ftc")
    rp.add_cli(parser.add_subparsers(dest="command", required=True))
    return parser


def test_cli_arguments_and_exit_codes(tmp_path, monkeypatch, capsys):
    avail = {"alpha": ok_reproduction("alpha"), "broken": failing_reproduction()}
    monkeypatch.setattr(rp, "available_reproductions", lambda: (avail, {}))
    args = _parser().parse_args(["reproduce", "alpha", "--out", str(tmp_path / "c1"), "--no-3d"])
    assert args.include_3d is False and args.force is False and args.func is rp.run_cli
    assert args.func(args) == 0
    args = _parser().parse_args(["reproduce", "all", "--out", str(tmp_path / "c2")])
    assert args.include_3d is True and args.func(args) == 1  # one paper failed
    args = _parser().parse_args(["reproduce", "nope", "--out", str(tmp_path / "c3")])
    assert args.func(args) == 2
    assert "unknown paper 'nope'; valid: alpha, broken, all" in capsys.readouterr().err
    (tmp_path / "c4").mkdir()
    (tmp_path / "c4" / "x").write_text("x")
    assert (
        args.func(_parser().parse_args(["reproduce", "alpha", "--out", str(tmp_path / "c4")])) == 2
    )
    assert (
        args.func(
            _parser().parse_args(["reproduce", "alpha", "--out", str(tmp_path / "c4"), "--force"])
        )
        == 0
    )
    with pytest.raises(SystemExit):  # --out is required
        _parser().parse_args(["reproduce", "alpha"])


def test_broken_paper_package_becomes_a_failed_section(tmp_path, monkeypatch):
    """A paper package that raises on import is reported, the others still register and run."""
    import formation_ftc.papers as papers_pkg

    pkg_dir = tmp_path / "plugins"
    pkg_dir.mkdir()
    (pkg_dir / "zzfake_good.py").write_text(
        "from report_fakes import ok_reproduction\n"
        "from formation_ftc.registry import register_reproduction\n"
        "register_reproduction(ok_reproduction('zzfake_good'))\n"
    )
    (pkg_dir / "zzfake_bad.py").write_text("raise ImportError('missing dependency xyz')\n")
    monkeypatch.setattr(papers_pkg, "__path__", list(papers_pkg.__path__) + [str(pkg_dir)])
    monkeypatch.setattr(
        registry,
        "plugin_modules",
        lambda: ["formation_ftc.papers.zzfake_bad", "formation_ftc.papers.zzfake_good"],
    )
    monkeypatch.setattr(registry, "_REPRODUCTIONS", {})
    monkeypatch.setattr(registry, "PLUGIN_ERRORS", {})
    monkeypatch.setattr(registry, "_LOADED", False)
    try:
        found, failures = rp.available_reproductions()
        assert list(found) == ["zzfake_good"]
        assert (
            list(failures) == ["zzfake_bad"] and "missing dependency xyz" in failures["zzfake_bad"]
        )
        # in this process: the monkeypatched registry does not exist in a spawned worker
        result = rp.reproduce(
            ["all"], tmp_path / "out", progress=False, console=_console(), workers=1
        )
    finally:
        for name in ("zzfake_good", "zzfake_bad"):
            sys.modules.pop(f"formation_ftc.papers.{name}", None)
    assert result["exit_code"] == 1
    assert result["papers"]["zzfake_bad"]["status"] == "failed"
    assert "missing dependency xyz" in result["papers"]["zzfake_bad"]["error"]
    assert result["papers"]["zzfake_good"]["status"] == "ok"


def test_papers_in_worker_processes_equal_one_after_the_other(tmp_path):
    """--workers 2: papers run in spawn worker processes (the longest first) and the report is the
    one the sequential run writes; a paper that raises in its worker is a failed section."""
    from report_fakes import shippable_reproduction

    avail = {
        "alpha": shippable_reproduction("alpha"),
        "gamma": shippable_reproduction("gamma", fail=True),
        "beta": shippable_reproduction("beta"),
    }
    seq, _ = _run(["all"], tmp_path / "seq", avail, workers=1)
    par, text = _run(["all"], tmp_path / "par", avail, workers=2, profile=True)
    assert seq["exit_code"] == par["exit_code"] == 1
    assert par["papers"]["gamma"]["status"] == "failed"
    assert "gamma exploded in its worker" in par["papers"]["gamma"]["error"]
    for paper in ("alpha", "beta"):
        a, b = (
            _read(tmp_path / "seq" / paper / "report.json"),
            _read(tmp_path / "par" / paper / "report.json"),
        )
        for key in (
            "rows",
            "checks",
            "figures",
            "verdicts",
            "summary" if "summary" in a else "seeds",
        ):
            assert a[key] == b[key], (paper, key)
        assert _read(tmp_path / "seq" / paper / "summary.json") == _read(
            tmp_path / "par" / paper / "summary.json"
        )
        assert (tmp_path / "par" / paper / "fig3.png").is_file()
    meta = _read(tmp_path / "par" / "summary.json")["metadata"]
    assert meta["papers"] == ["alpha", "gamma", "beta"] and meta["paper_workers"] == 2
    assert meta["paper_worker_cpu_threads"] == rp._worker_threads(2)
    assert set(par["profile"]) >= {"alpha", "beta"} and "side by side" in meta["profile_method"]


def test_worker_threads_share_the_cores(monkeypatch):
    monkeypatch.delenv("PJRT_NPROC", raising=False)  # the test run sets it for its own workers
    cores = len(os.sched_getaffinity(0))
    assert rp._worker_threads(1) == str(cores)
    assert rp._worker_threads(2) == str(max(1, cores // 2))
    assert rp._worker_threads(10 * cores) == "1"
    # set for the workers started inside the block only; a value the user set is kept
    with rp._threads_for_workers(10 * cores):
        assert os.environ["PJRT_NPROC"] == "1"
    assert "PJRT_NPROC" not in os.environ
    monkeypatch.setenv("PJRT_NPROC", "7")
    assert rp._worker_threads(2) == "7"
    with rp._threads_for_workers(2):
        assert os.environ["PJRT_NPROC"] == "7"
    assert os.environ["PJRT_NPROC"] == "7"


def test_paper_workers_count():
    assert rp._paper_workers(None, 1) == 1
    assert rp._paper_workers(3, 2) == 2
    with pytest.raises(rp.ReproduceError, match="--workers must be >= 1"):
        rp._paper_workers(0, 5)
