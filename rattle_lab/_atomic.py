"""Atomic output: write to a temporary file beside the target, then rename.

An interrupted run (exception, Ctrl-C, kill) leaves the previous result intact,
because ``os.replace`` is atomic on POSIX and Windows within one filesystem.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .exceptions import OutputError


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path; on success rename it onto ``target``.

    The temporary file already has the mode the result should have: that of
    the file it replaces, or that of a new file (0o666 less the umask).

    Parameters
    ----------
    target : path-like
        The final output path.  Its directory must exist.
    suffix : str, optional
        Suffix of the temporary file (defaults to the target's suffix, so that
        libraries which look at the extension, like matplotlib, behave).

    Raises
    ------
    OutputError
        If the directory does not exist or the rename fails.
    """
    target = Path(target)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise OutputError(f"{target}: output directory {directory} does not exist")
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=suffix if suffix is not None else target.suffix + ".tmp",
        dir=directory,
    )
    try:
        # mkstemp makes the file 0o600; the result should have the mode of the file it
        # replaces, or else that of any new file (0o666 less the umask).
        try:
            mode = stat.S_IMODE(os.stat(target).st_mode)
        except OSError:
            mode = 0o666 & ~_umask()
        os.fchmod(fd, mode)
    finally:
        os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def _umask() -> int:
    try:  # Linux: read it without changing it (os.umask would, briefly, for every thread)
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write_text(target: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``target`` atomically (UTF-8)."""
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
