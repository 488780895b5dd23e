"""Atomic output: write to a temporary file beside the target, then rename.

An interrupted run (exception, Ctrl-C, SIGTERM) leaves the previous result
intact, because ``os.replace`` is atomic on POSIX and Windows within one
filesystem, and the temporary file is removed on the way out.

Temporary files are named ``.<target name>.rattle-tmp-<pid>-<random><suffix>``:
recognisable, and carrying the writer's process id.  A writer killed outright
(``kill -9``, power loss) cannot remove its file; the next :func:`atomic_path`
in the same folder removes every such file whose writer is gone
(:func:`remove_stale_temporaries`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import re
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rattle_lab.exceptions import OutputError

#: Marker in the name of every temporary file this package writes.
TMP_MARKER = ".rattle-tmp-"
_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS}
_TMP_RE = re.compile(r"^\..*" + re.escape(TMP_MARKER) + r"(\d+)-")


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def remove_stale_temporaries(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files in ``directory`` whose writer process is gone.

    Returns the paths removed.  Files of live writers (this process included)
    are left alone; a folder that cannot be listed is skipped silently.
    """
    removed: list[Path] = []
    try:
        names = os.listdir(directory)
    except OSError:
        return removed
    for name in names:
        match = _TMP_RE.match(name)
        if match is None or _pid_alive(int(match.group(1))):
            continue
        path = Path(directory) / name
        with contextlib.suppress(OSError):
            path.unlink()
            removed.append(path)
    return removed


_HELD = (signal.SIGINT, signal.SIGTERM)


def _hold_signals() -> set[int | signal.Signals] | None:
    """Block Ctrl-C and SIGTERM in this thread (they stay pending); the previous mask."""
    if not hasattr(signal, "pthread_sigmask"):  # not POSIX: nothing to hold
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, _HELD)


def _release_signals(previous: set[int | signal.Signals] | None) -> None:
    """Restore the mask :func:`_hold_signals` returned (a pending signal is delivered)."""
    if previous is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def check_output_path(target: str | os.PathLike[str]) -> Path:
    """The directory ``target`` will be written in; refused before any work is done.

    Raises
    ------
    OutputError
        If the directory does not exist or ``target`` is a directory: one line naming it.
    """
    target = Path(target)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise OutputError(f"{target}: output directory {directory} does not exist")
    if target.is_dir():
        raise OutputError(f"{target}: is a directory; give a file name for the output")
    return directory


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
        If the directory does not exist, ``target`` is a directory, or the
        temporary file cannot be created, written or renamed (read-only
        folder, full disk): one line naming the target.
    """
    target = Path(target)
    directory = check_output_path(target)
    remove_stale_temporaries(directory)
    # Ctrl-C and SIGTERM are held from the temporary file's creation until the clean-up below
    # is in place (a signal in between left the file behind); one that came meanwhile lands
    # inside it.
    held = _hold_signals()
    try:
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{target.name}{TMP_MARKER}{os.getpid()}-",
            suffix=suffix if suffix is not None else target.suffix, dir=directory)
    except OSError as exc:
        _release_signals(held)
        raise OutputError(f"{target}: cannot write in {directory}: "
                          f"{exc.strerror or exc}") from exc
    tmp = Path(tmp_name)
    try:
        try:
            _release_signals(held)
            # mkstemp makes the file 0o600; the result should have the mode of the file it
            # replaces, or else that of any new file (0o666 less the umask).
            try:
                mode = stat.S_IMODE(os.stat(target).st_mode)
            except OSError:
                mode = 0o666 & ~_umask()
            os.fchmod(fd, mode)
        finally:
            os.close(fd)
        yield tmp
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        # A full disk or a read-only filesystem is the output's problem; other OSErrors
        # may come from reading inputs inside the block and keep their own message.
        if (isinstance(exc, OSError) and not isinstance(exc, OutputError)
                and exc.errno in _WRITE_ERRNOS):
            raise output_error(target, exc) from exc
        raise


def output_error(target: str | os.PathLike[str], exc: OSError) -> OutputError:
    """One-line :class:`OutputError` for an OSError met while writing ``target``."""
    if exc.errno == errno.ENOSPC:
        why = "no space left on the device"
    elif exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        why = "permission denied (read-only folder or file?)"
    elif exc.errno == errno.EISDIR:
        why = "is a directory"
    else:
        why = " ".join(str(exc.strerror or exc).split())
    return OutputError(f"{target}: cannot write: {why}")


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
