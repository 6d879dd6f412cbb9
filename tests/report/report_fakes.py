"""Fake paper reproductions for the report tests (no simulation: they only write files and reports).

PNG files are built byte by byte (zlib + CRC) so their pixel size is an independent truth the
browser test can compare with the decoded ``naturalWidth``/``naturalHeight``.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from formation_ftc.registry import ComparisonRow, Condition, Figure, PaperReport, Reproduction
from formation_ftc.report.html import write_trajectory3d


def tiny_png(width: int, height: int, rgb: tuple[int, int, int] = (30, 120, 200)) -> bytes:
    """A valid truecolour PNG of ``width`` x ``height`` pixels filled with ``rgb``."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    raw = b"".join(b"\x00" + bytes(rgb) * width for _ in range(height))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b"")
    )


def ok_reproduction(
    paper: str = "alpha",
    *,
    figure_sizes=((40, 30), (24, 18)),
    trajectory: bool = False,
    calls: list | None = None,
    summary_extra: dict | None = None,
) -> Reproduction:
    """A reproduction that writes ``len(figure_sizes)`` PNGs and returns a complete report."""

    def run(out_dir: Path, progress) -> PaperReport:
        if calls is not None:
            calls.append((paper, Path(out_dir)))
        progress(0.0, "start")
        figures = []
        for k, (w, h) in enumerate(figure_sizes, start=3):
            name = f"fig{k}.png"
            (Path(out_dir) / name).write_bytes(tiny_png(w, h))
            figures.append(
                Figure(name, str(k), f"{paper} figure {k}: positions <x_i> & velocities")
            )
            progress(k / (len(figure_sizes) + 3), f"figure {k}")
        if trajectory:
            t = np.linspace(0.0, 2 * np.pi, 50)
            write_trajectory3d(
                out_dir,
                {
                    "SC1": np.c_[np.cos(t), np.sin(t), 0.1 * t],
                    "SC2": np.c_[2 * np.cos(t), np.sin(t), -0.1 * t],
                },
                title=f"{paper} formation (LVLH)",
            )
        progress(1.0, "done")
        summary = {
            "tracking_error_m": np.float64(0.0125),
            "settled": True,
            "series": np.arange(3),
            "undefined": float("nan"),
        }
        summary.update(summary_extra or {})
        return PaperReport(
            paper=paper,
            summary=summary,
            rows=[
                ComparisonRow.judged(
                    "settling time",
                    "10 s (Fig. 3)",
                    "9.8 s",
                    "within 5 %",
                    (("rel<=", 9.8, 10.0, 0.05),),
                ),
                ComparisonRow.judged(
                    "peak thrust",
                    "",
                    "0.9 N",
                    "within 5 % of the reference",
                    (("rel<=", 0.9, 0.5, 0.05),),
                    "saturation",
                    reference="0.5 N (reference run, docs/references.md)",
                ),
                ComparisonRow("chattering", "-", "small", "-", "not stated"),
            ],
            figures=figures,
            checks=[
                Condition(
                    "Laplacian connected",
                    "Assumption 1",
                    "lambda2 = 0.38",
                    "> 0",
                    True,
                    basis="exact",
                ),
                Condition(
                    "gain bound",
                    "Thm 1 eq. (23)",
                    "k = 0.2",
                    "k > 0.5",
                    False,
                    detail="too small",
                    basis="exact",
                ),
                Condition(
                    "delay bound",
                    "Thm 2",
                    "n/a",
                    "T < 1 s",
                    None,
                    required=False,
                    basis="informative",
                ),
            ],
            scenarios=[f"{paper}-thm1"],
            seeds=[7, 8],
            notes=[f"{paper} note"],
        )

    return Reproduction(
        paper=paper,
        title=f"Paper {paper.title()} (2020)",
        citation=f"{paper} et al., J. Test 1 (2020)",
        description=f"Adaptive law of {paper}.\n\nSecond paragraph <em>escaped</em>.",
        errata=[("E001-01", f"{paper}: sign of eq. (7) corrected")],
        run=run,
    )


def failing_reproduction(paper: str = "broken", message: str = "solver exploded") -> Reproduction:
    def run(out_dir: Path, progress) -> PaperReport:
        progress(0.3, "about to fail")
        raise RuntimeError(message)

    return Reproduction(
        paper=paper,
        title="Broken paper",
        citation="Nobody (1999)",
        description="Fails.",
        errata=[],
        run=run,
    )


def wrong_type_reproduction(paper: str = "wrongtype") -> Reproduction:
    return Reproduction(
        paper=paper,
        title="Wrong type",
        citation="",
        description="",
        errata=[],
        run=lambda out_dir, progress: {"not": "a PaperReport"},
    )


def _shipped_run(paper: str, out_dir: Path, progress) -> PaperReport:
    """Module-level run (picklable through functools.partial): what a worker process receives."""
    progress(0.5, "half")
    (Path(out_dir) / "fig3.png").write_bytes(tiny_png(8, 6))
    return PaperReport(
        paper=paper,
        summary={"value": len(paper), "undefined": float("nan")},
        rows=[ComparisonRow.judged("value", "", str(len(paper)), ">= 1", ((">=", len(paper), 1),))],
        figures=[Figure("fig3.png", "3", f"{paper} figure")],
        checks=[Condition("positive", "Thm 1", "1", "> 0", True, basis="exact")],
        scenarios=[f"{paper}-s"],
        seeds=[1],
        notes=[],
    )


def _shipped_failure(paper: str, out_dir: Path, progress) -> PaperReport:
    raise RuntimeError(f"{paper} exploded in its worker")


def shippable_reproduction(paper: str, fail: bool = False) -> Reproduction:
    """A fake that can be pickled into a worker process (no closures)."""
    import functools

    run = functools.partial(_shipped_failure if fail else _shipped_run, paper)
    return Reproduction(
        paper=paper, title=paper, citation=f"{paper} (2020)", description="", errata=[], run=run
    )
