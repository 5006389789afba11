"""Atomic file replacement: write to a temporary file in the same folder, then rename.

A crash, an exception or a full disk while writing leaves the previous file (if any)
untouched and no half-written file under the target name.

The temporary file is named after its owner, ``.<name>.<pid>-<start>-<host>.<random>.tmp``:
the writing process's id, its start time (clock ticks since boot, ``0`` where the system
does not tell) and a hash of the machine's name. A process killed while writing leaves
its temporary behind; :func:`remove_stale_temporaries` removes those whose owner is
provably gone (no such process on this machine, or a process of that id started at another
time: the id was reused) and never those of a live writer, so that runs writing into one
folder at the same time (``hdrjax batch``) do not delete each other's files.
"""

import contextlib
import functools
import hashlib
import os
import re
import socket
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _proc_stat(pid: int) -> tuple[str, str] | None:
    """``(state, start time)`` of process ``pid`` from ``/proc`` (Linux); ``None`` when
    the process does not exist or the system has no ``/proc``."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            text = f.read().decode("ascii", "replace")
    except OSError:
        return None
    # fields after the command name (which may hold spaces and parentheses): proc(5)
    fields = text[text.rfind(")") + 2 :].split()
    return (fields[0], fields[19]) if len(fields) > 19 else None


@functools.cache
def _host() -> str:
    return hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]


def owner_token(pid: int) -> str:
    """``<pid>-<start>-<host>``: process ``pid`` of this machine as the owner of a
    temporary file (see the module doc)."""
    stat = _proc_stat(pid)
    return f"{pid}-{stat[1] if stat else 0}-{_host()}"


@functools.cache
def _own_token(pid: int) -> str:
    return owner_token(pid)  # keyed by the id: a forked child computes its own


_TOKEN = re.compile(r"(\d+)-(\d+)-([0-9a-f]{8})")


def owner_alive(token: str) -> bool:
    """Whether the owner of a temporary file may still be writing it: ``False`` only when
    it is provably gone; an unknown token, another machine or a system that cannot tell
    count as alive."""
    m = _TOKEN.fullmatch(token)
    if m is None or m[3] != _host() or os.name != "posix":
        return True
    pid, start = int(m[1]), m[2]
    if pid == os.getpid():
        return token == _own_token(pid)
    try:
        os.kill(pid, 0)  # signal 0: existence check only
    except ProcessLookupError:
        return False
    except OSError:
        return True  # another user's process (EPERM): /proc may hide its start time
    stat = _proc_stat(pid)
    if stat is None:  # no /proc (start time unknown), or the process ended meanwhile
        return start == "0" or not os.path.isdir("/proc/self")
    state, now = stat
    return state not in ("Z", "X") and (start == "0" or now == start)


def remove_stale_temporaries(paths: str | os.PathLike | Iterable[str | os.PathLike]) -> list[Path]:
    """Remove the temporary files of ``paths`` (one file or many) left by writers that
    are gone.

    Temporaries of live writers (this process included) and of other machines, and files
    not named as :func:`atomic_path` names them, are left alone. Each folder is listed once.

    Returns:
        The files removed.
    """
    items = [paths] if isinstance(paths, (str, os.PathLike)) else paths
    wanted: dict[Path, set[str]] = {}
    for p in map(Path, items):
        wanted.setdefault(p.parent if str(p.parent) else Path("."), set()).add(p.name)
    removed = []
    for folder, names in wanted.items():
        try:
            entries = os.listdir(folder)
        except OSError:
            continue
        for entry in entries:
            if not (entry.startswith(".") and entry.endswith(".tmp")):
                continue
            parts = entry[1 : -len(".tmp")].rsplit(".", 2)  # name, owner, random part
            if len(parts) == 3 and parts[0] in names and not owner_alive(parts[1]):
                with contextlib.suppress(OSError):
                    (folder / entry).unlink()
                    removed.append(folder / entry)
    return removed


def file_identity(path: str | os.PathLike) -> tuple:
    """What ``path`` names, for telling whether two paths are one file: device and inode
    when it exists (symbolic and hard links to a file compare equal to it), else the
    resolved path. Two paths are the same file when their identities are equal."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return ("path", os.path.realpath(path))
    return ("inode", st.st_dev, st.st_ino)


_LIVE: set[Path] = set()
"""The temporary files :func:`atomic_path` is writing now (the command line removes them
when Ctrl-C ends the process while its main thread is blocked: :mod:`hdrjax.cli._interrupt`)."""


def remove_live_temporaries() -> None:
    """Remove the temporary files of :func:`atomic_path` still being written."""
    for tmp in list(_LIVE):
        with contextlib.suppress(OSError):
            tmp.unlink()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, overwrite: bool = True) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it onto ``path`` on success.

    Args:
        path: the final file name.
        overwrite: when ``False``, refuse (``FileExistsError``) if ``path`` exists.

    Raises:
        FileExistsError: ``path`` exists and ``overwrite`` is ``False``.
        FileNotFoundError: the folder of ``path`` does not exist.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not overwrite and path.exists():
        raise FileExistsError(f"{path}: already exists (pass overwrite=True to replace it)")
    if not folder.is_dir():
        raise FileNotFoundError(f"{path}: folder {folder} does not exist")
    prefix = f".{path.name}.{_own_token(os.getpid())}."
    fd, tmp_name = tempfile.mkstemp(prefix=prefix, suffix=".tmp", dir=folder)
    os.close(fd)
    tmp = Path(tmp_name)
    _LIVE.add(tmp)
    try:
        yield tmp
        if not tmp.exists() or tmp.stat().st_size == 0:
            raise OSError(f"{path}: nothing was written")
        os.chmod(tmp, 0o666 & ~_umask())
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        if not overwrite and path.exists():
            raise FileExistsError(f"{path}: already exists (pass overwrite=True to replace it)")
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    finally:
        _LIVE.discard(tmp)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, *, overwrite: bool = True) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
    return Path(path)


__all__ = ["atomic_path", "atomic_write_bytes", "file_identity", "remove_stale_temporaries"]
