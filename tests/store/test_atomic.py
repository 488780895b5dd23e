"""Atomic outputs: the previous result survives an error; modes are those of ordinary files."""

from __future__ import annotations

import os
import stat

import pytest

from rattle_lab._atomic import atomic_path, atomic_write_text
from rattle_lab.exceptions import OutputError


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_a_new_file_gets_the_umask_mode(tmp_path):
    old = os.umask(0o027)
    try:
        atomic_write_text(tmp_path / "a.txt", "hello")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").read_text() == "hello"
    assert _mode(tmp_path / "a.txt") == 0o640  # 0o666 less the umask, not mkstemp's 0o600


def test_a_replaced_file_keeps_its_mode(tmp_path):
    target = tmp_path / "b.txt"
    target.write_text("old")
    os.chmod(target, 0o664)
    atomic_write_text(target, "new")
    assert target.read_text() == "new" and _mode(target) == 0o664


def test_an_error_leaves_the_previous_result_and_no_temporary_file(tmp_path):
    target = tmp_path / "c.txt"
    target.write_text("previous")
    with pytest.raises(RuntimeError, match="interrupted"):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted")
    assert target.read_text() == "previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.txt"]


def test_a_missing_directory_is_an_output_error(tmp_path):
    with pytest.raises(OutputError, match=r"output directory .*nowhere does not exist"):
        with atomic_path(tmp_path / "nowhere" / "d.txt"):
            pass
