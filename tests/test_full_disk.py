"""A full disk (``ENOSPC``): exit status 3 with one line naming the path, no traceback file, the earlier
result kept and no staging directory left.

The end-to-end cases mount a small tmpfs (root only; skipped with the reason elsewhere), fill it and run
the command line in this process (``formation_ftc.cli.main``), so the closed loop compiles once for all
of them. Before the NetCDF file was built in memory (``formation_ftc.cf.netcdf_bytes``), HDF5 writing
onto a full disk crashed the interpreter (a segmentation fault) and left the staging directory behind."""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from formation_ftc import exitcodes
from formation_ftc.runout import MARKER, staged_output


def _no_space(path: str | None = None) -> OSError:
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)


def test_staged_output_on_a_full_disk_removes_the_stage_and_names_the_directory(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "metrics.json").write_text("earlier")
    with pytest.raises(OSError) as info, staged_output(out) as stage:
        (stage / "result.nc").write_bytes(b"partial")
        raise _no_space()  # what a write without a file name raises
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(out)
    assert "keeps its earlier result" in info.value.strerror
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no .run.tmp-PID
    assert (out / "metrics.json").read_text() == "earlier"


@pytest.mark.parametrize("as_json", [False, True])
def test_a_full_disk_is_one_line_and_status_3_without_a_traceback_file(
    tmp_path, monkeypatch, capsys, as_json
):
    monkeypatch.setenv("FORMATION_FTC_CRASH_DIR", str(tmp_path / "crash"))

    def command(args):
        raise _no_space(str(tmp_path / "out"))

    args = type("Args", (), {"json": as_json})()
    assert exitcodes.run_guarded(command, args) == exitcodes.EXIT_UNEXPECTED
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"error: no space left on {tmp_path / 'out'}; free space there or write elsewhere"
    ]
    if as_json:
        assert json.loads(captured.out)["exit_code"] == 3
    assert not (tmp_path / "crash").exists()  # nothing written: it would need the missing space
    # any other OSError of a result file stays an unexpected error with its traceback file
    assert exitcodes.run_guarded(lambda a: open(tmp_path / "no" / "such", "rb"), args) == 3
    assert len(list((tmp_path / "crash").iterdir())) == 1


@pytest.fixture
def small_disk(tmp_path):
    """A 6 MiB tmpfs, unmounted afterwards."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    mnt = tmp_path / "disk"
    mnt.mkdir()
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=6m", "tmpfs", str(mnt)],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        pytest.skip(f"mount not permitted here: {done.stderr.strip()}")
    yield mnt
    subprocess.run(["umount", "-l", str(mnt)], check=False)


def _fill(disk: Path, leave_kib: int) -> None:
    """Fill ``disk`` up to ``leave_kib`` KiB of free space."""
    st = os.statvfs(disk)
    free = st.f_bavail * st.f_frsize
    with open(disk / "filler", "ab") as f:
        f.write(b"\0" * max(0, free - leave_kib * 1024))


def _main(capfd, *argv: str) -> tuple[int, list[str]]:
    from formation_ftc.cli import main

    code = main(list(argv))
    return code, [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]


# --figures: the figures and the 3-D view (plotly's 4.8 MB script) are written too
_RUN = ("-q", "run", "cw-free-drift", "--figures", "--set", "simulation.horizon=100", "--out")


@pytest.mark.parametrize(
    "leave_kib, in_process",
    [
        (8, False),  # HDF5 ran out half-way through result.nc (23 KB): the segmentation fault
        (0, True),  # no file can be created
        (200, True),  # the figures
        (1500, True),  # the page's script
    ],
)
def test_run_on_a_full_disk_exits_3_and_keeps_the_earlier_result(
    small_disk, capfd, monkeypatch, leave_kib, in_process
):
    monkeypatch.setenv("FORMATION_FTC_CRASH_DIR", str(small_disk / "crash"))
    out = small_disk / "r"
    out.mkdir()
    earlier = {"result.nc": b"earlier result", "metrics.json": b'{"earlier": 1}'}
    for name, data in earlier.items():
        (out / name).write_bytes(data)
    (out / MARKER).write_text(json.dumps({"files": sorted(earlier)}))
    _fill(small_disk, leave_kib)
    if in_process:
        code, err = _main(capfd, *_RUN, str(out))
    else:
        done = subprocess.run(
            [sys.executable, "-m", "formation_ftc", *_RUN, str(out)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        code, err = done.returncode, [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert code == 3
    assert err == [
        f"error: no space left on {out} (it keeps its earlier result); free space there or write "
        "elsewhere"
    ]
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name != MARKER} == earlier
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler", "r"]  # no .r.tmp-PID
    # with the space back, the same command writes the new result
    (small_disk / "filler").unlink()
    code, _ = _main(capfd, *_RUN, str(out))
    assert code == 0 and json.loads((out / "metrics.json").read_text()).get("scenario")


#: the tiny campaign of tests/campaign/conftest.py (TINY): its compiled programs are shared
TINY_CAMPAIGN = Path(__file__).parent / "campaign" / "tiny-campaign.toml"


def test_campaign_on_a_full_disk_exits_3_with_one_line(small_disk, capfd):
    out = small_disk / "c"
    _fill(small_disk, 16)  # room for the manifest (2 KB), not for a trace file (28 KB)
    code, err = _main(capfd, "-q", "campaign", "run", str(TINY_CAMPAIGN), "--out", str(out))
    assert code == 3
    errors = [
        ln for ln in err if "error" in ln.lower() or "Traceback" in ln
    ]  # (and a progress bar)
    assert len(errors) == 1 and errors[0].startswith(f"error: no space left on {out}/"), err
    assert not [p for p in out.rglob("*") if ".tmp-" in p.name]
