"""formation_ftc.atomic.atomic_write: a reader sees the old file or the whole new one; a failure at any
step (a full disk, an interrupt) leaves the old content and no temporary file."""

from __future__ import annotations

import doctest
import errno
import os

import pytest

from formation_ftc import atomic
from formation_ftc.atomic import atomic_write, temporary_name


def test_doctest():
    assert doctest.testmod(atomic).failed == 0


def test_text_bytes_and_writer_function(tmp_path):
    p = tmp_path / "f.json"
    assert atomic_write(p, "é") == p and p.read_bytes() == "é".encode()
    atomic_write(p, b"\x00\x01")
    assert p.read_bytes() == b"\x00\x01"
    atomic_write(p, lambda tmp: tmp.write_text("by a writer"))
    assert p.read_text() == "by a writer"
    assert sorted(q.name for q in tmp_path.iterdir()) == ["f.json"]


@pytest.mark.parametrize("step", ["write", "fsync", "replace"])
def test_disk_full_at_any_step_keeps_the_old_file(tmp_path, monkeypatch, step):
    p = tmp_path / "f.txt"
    p.write_text("old")
    full = OSError(errno.ENOSPC, "No space left on device")

    def fail(*args, **kwargs):
        raise full

    if step == "write":

        def data(tmp):  # a writer function that runs out of space half-way
            tmp.write_text("ne")
            raise full

    else:
        data = "new"
        monkeypatch.setattr(os, step, fail)
    with pytest.raises(OSError, match="No space left"):
        atomic_write(p, data)
    monkeypatch.undo()
    assert p.read_text() == "old"
    assert not temporary_name(p).exists() and sorted(q.name for q in tmp_path.iterdir()) == [
        "f.txt"
    ]


def test_interrupt_removes_the_temporary_file(tmp_path):
    p = tmp_path / "f.txt"

    def interrupted(tmp):
        tmp.write_text("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(p, interrupted)
    assert not p.exists() and list(tmp_path.iterdir()) == []
