"""``formation-ftc reproduce --profile``: per-paper phase breakdown (compile, run, post, plot, report).

Truths: sleeps of known length inside the fake reproduction's marked blocks (a lower bound on each
phase), a freshly defined jitted function (JAX must trace and compile it: compile > 0, and that time
is not counted as run), the fake's own wall-clock measurement, and synthetic compile spans for the
interval arithmetic of :class:`Profiler`.
"""

from __future__ import annotations

import argparse
import io
import json
import time
from pathlib import Path

import jax
import jax.numpy as jnp
from report_fakes import ok_reproduction
from rich.console import Console

from formation_ftc.registry import PaperReport, Reproduction
from formation_ftc.report import profile as pf
from formation_ftc.report import reproduce as rp

RUN_SLEEP, PLOT_SLEEP, POST_SLEEP = 0.20, 0.15, 0.10


def _profiled_reproduction(paper: str, measured: dict) -> Reproduction:
    base = ok_reproduction(paper)

    def run(out_dir: Path, progress) -> PaperReport:
        t0 = time.perf_counter()
        salt = (
            time.perf_counter_ns() % 1000
        )  # a new program every call: never in the in-memory jit cache
        with pf.phase("run"):
            f = jax.jit(lambda x: jnp.cumsum(jnp.sin(x * salt)) @ jnp.cos(x))
            f(jnp.arange(64.0)).block_until_ready()
            time.sleep(RUN_SLEEP)
        time.sleep(POST_SLEEP)
        with pf.phase("plot"):
            time.sleep(PLOT_SLEEP)
        report = base.run(out_dir, progress)
        measured[paper] = time.perf_counter() - t0
        return report

    return Reproduction(
        paper=paper,
        title=base.title,
        citation=base.citation,
        description=base.description,
        errata=base.errata,
        run=run,
    )


def test_profile_table_and_metadata(tmp_path):
    measured: dict = {}
    avail = {p: _profiled_reproduction(p, measured) for p in ("alpha", "beta")}
    console = Console(file=io.StringIO(), width=160)
    result = rp.reproduce(
        ["all"], tmp_path / "r", available=avail, progress=False, console=console, profile=True
    )
    text = console.file.getvalue()
    assert result["exit_code"] == 0
    assert "wall time per phase" in text
    header = next(line for line in text.splitlines() if "compile" in line and "plot" in line)
    for col in ("paper", "compile", "run", "post", "plot", "report", "total"):
        assert col in header
    assert any(line.strip("│ ").startswith("alpha") for line in text.splitlines() if "│" in line)
    assert "index.html" in text

    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    prof = summary["metadata"]["profile"]
    assert set(prof) == {"alpha", "beta"} and prof == {
        p: result["profile"][p] for p in ("alpha", "beta")
    }
    for paper, b in prof.items():
        assert set(b) == {*pf.PHASES, "total"}
        assert b["compile"] > 0.0  # the fresh jitted function was traced and compiled
        assert RUN_SLEEP - 0.01 <= b["run"] < RUN_SLEEP + 1.0  # compile is not counted as run
        assert b["plot"] >= PLOT_SLEEP - 0.01 and b["post"] >= POST_SLEEP - 0.01
        assert b["report"] > 0.0  # report.json / summary.json of the paper
        assert abs(sum(b[k] for k in pf.PHASES) - b["total"]) < 0.01  # every second counted once
        assert b["total"] >= measured[paper] - 0.01
        assert summary["metadata"][f"profile_{paper}"] == pf.format_breakdown(b)
    html = (tmp_path / "r" / "index.html").read_text()
    assert "profile_alpha" in html and "profile_method" in html  # in the run-metadata section


def test_without_profile_nothing_is_recorded(tmp_path):
    console = Console(file=io.StringIO(), width=160)
    result = rp.reproduce(
        ["alpha"],
        tmp_path / "r",
        available={"alpha": ok_reproduction("alpha")},
        progress=False,
        console=console,
    )
    assert "profile" not in result and "per phase" not in console.file.getvalue()
    meta = json.loads((tmp_path / "r" / "summary.json").read_text())["metadata"]
    assert not any(k.startswith("profile") for k in meta)
    with pf.phase("run"):  # no active profiler: a plain block
        assert pf.active() is None


def test_cli_profile_flag_prints_the_table(tmp_path, monkeypatch, capsys):
    avail = {"alpha": ok_reproduction("alpha")}
    monkeypatch.setattr(rp, "available_reproductions", lambda: (avail, {}))
    parser = argparse.ArgumentParser(prog="formation-ftc")
    rp.add_cli(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["reproduce", "alpha", "--out", str(tmp_path / "p"), "--profile"])
    assert args.profile is True
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "wall time per phase" in out and "compile" in out and "report" in out
    assert parser.parse_args(["reproduce", "alpha", "--out", str(tmp_path / "q")]).profile is False


def test_profiler_nesting_and_compile_overlap():
    prof = pf.Profiler()
    prof.start = 100.0
    # run 100-104 with plot 101-102 nested inside; compile spans 100.5-101.5 (half in run, half in
    # plot) and 103-103.5 nested twice (a trace inside a trace) -> merged compile 1.5 s
    prof.segments = [("run", 100.0, 101.0), ("plot", 101.0, 102.0), ("run", 102.0, 104.0)]
    prof.compile_spans = [(100.5, 101.5), (103.0, 103.5), (103.1, 103.2)]
    prof.end = 105.0
    b = prof.breakdown()
    assert b["compile"] == 1.5
    assert b["run"] == 2.0  # 1 + 2 s of run segments minus 0.5 + 0.5 s of compile
    assert b["plot"] == 0.5
    assert b["post"] == 1.0  # 104-105 outside every phase
    assert b["report"] == 0.0 and b["total"] == 5.0


def test_profiler_stack_pauses_outer_phase():
    with pf.Profiler() as prof:
        with pf.phase("run"):
            time.sleep(0.05)
            with pf.phase("plot"):
                time.sleep(0.1)
            time.sleep(0.05)
    assert pf.active() is None
    names = [s[0] for s in prof.segments]
    assert names == ["run", "plot", "run"]
    b = prof.breakdown()
    assert 0.095 <= b["run"] < 0.5 and 0.095 <= b["plot"] < 0.5
    # the segments do not overlap: their durations add up to at most the wall time
    assert sum(e - s for _, s, e in prof.segments) <= prof.end - prof.start + 1e-9
