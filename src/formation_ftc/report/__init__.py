"""Reproduction report: ``formation-ftc reproduce PAPER|all --out DIR``.

Runs the registered paper reproductions (:class:`formation_ftc.registry.Reproduction`) under one
progress bar, measures each paper's wall time, and writes ``DIR/index.html`` (a self-contained
static page: method, published-vs-reproduced table, figures, condition checks, errata, run
metadata, optional interactive 3-D trajectories), ``DIR/summary.json`` and per-paper
``report.json`` / ``summary.json``.

Modules: :mod:`~formation_ftc.report.reproduce` (orchestration and the CLI subcommand),
:mod:`~formation_ftc.report.html` (the page), :mod:`~formation_ftc.report.metadata` (provenance).
A reproduction that wants an interactive 3-D view calls :func:`write_trajectory3d` on its output
directory. The driver is ``formation_ftc.report.reproduce.reproduce(papers, out, force, progress)``.
"""

from __future__ import annotations

from formation_ftc.report.html import render_index, write_index, write_trajectory3d
from formation_ftc.report.metadata import provenance
from formation_ftc.report.reproduce import (
    MARKER_NAME,
    ReproduceError,
    add_cli,
    run_cli,
    to_jsonable,
)

# ``formation_ftc.report.reproduce`` stays the submodule (the CLI calls
# ``formation_ftc.report.reproduce.add_cli``); the driver is ``formation_ftc.report.reproduce.reproduce``.

__all__ = [
    "MARKER_NAME",
    "ReproduceError",
    "add_cli",
    "provenance",
    "render_index",
    "run_cli",
    "to_jsonable",
    "write_index",
    "write_trajectory3d",
]
