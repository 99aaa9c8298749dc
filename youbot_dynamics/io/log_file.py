"""Log files taken exclusively, written without buffering, and what a failed write leaves.

- :func:`open_exclusive` opens (creating) a log path under an advisory lock: ``flock``
  ``LOCK_EX | LOCK_NB`` on the file itself, taken before the file is emptied, so a second
  writer on the same path (another process, or another logger in this one) is refused with
  :class:`LogPathInUse` (one line naming the path and the holder's pid, read from
  ``/proc/locks``) and the first writer's log stays intact. The kernel drops the lock when
  the file is closed or its process dies (``kill -9`` included), so a crashed writer's
  file can be recovered and its path reused. Any other refusal to open (a directory, a
  read-only file system, no permission) is :class:`LogPathError`, also one line.
- :class:`FileSink` writes to that descriptor with no buffer of its own: every ``write``
  reaches the kernel whole or raises ``OSError``, and ``offset`` is always the bytes the
  file really holds, so after a failed write (ENOSPC, EIO, EROFS, EDQUOT, EFBIG) the writer
  knows where its last complete record ends.
- :func:`room_left` is what a log file may still grow by (free space, file-size limit), for
  a writer that cannot see its own write errors (Rerun's) and must stop before them.
- :class:`LogWriteFailed` is what a logger reports once a write failed and logging stopped:
  the errno's name and text, the path, what the file holds, what was lost, and whether
  the file was finalised (readable as it is) or needs ``youbot-dynamics log recover``.
"""
from __future__ import annotations

import errno
import fcntl
import os
import resource
from dataclasses import dataclass
from pathlib import Path

from youbot_dynamics.errors import UserInputError


class LogPathError(UserInputError):
    """A log path that cannot be opened for writing: the message names the path and the
    reason (errno name and text)."""


class LogPathInUse(LogPathError):
    """A log path another writer holds (its advisory lock): the message names the path and
    the holder's pid."""


def errno_name(error: OSError) -> str:
    """``ENOSPC``, ``EIO``, ... for ``error`` (``OSError`` if it carries no errno)."""
    return errno.errorcode.get(error.errno, "OSError") if error.errno is not None else "OSError"


def describe_os_error(error: OSError) -> str:
    """``ENOSPC (No space left on device)``: the errno's name and text."""
    return f"{errno_name(error)} ({error.strerror or error})"


def lock_holder_pid(fd: int) -> int | None:
    """The pid holding a ``flock`` on the file open as ``fd``, from ``/proc/locks`` (Linux);
    None if it cannot be told."""
    status = os.fstat(fd)
    inode = f"{os.major(status.st_dev):02x}:{os.minor(status.st_dev):02x}:{status.st_ino}"
    try:
        with open("/proc/locks", encoding="ascii") as locks:
            for line in locks:
                fields = line.split()          # "1: FLOCK  ADVISORY  WRITE 19034 fe:00:2146503 0 EOF"
                if len(fields) >= 6 and fields[1] == "FLOCK" and fields[5] == inode and fields[4].isdigit():
                    return int(fields[4])
    except OSError:
        return None
    return None


def open_exclusive(path: Path, kind: str, *, truncate: bool = True) -> int:
    """Open (create) ``path`` for writing under an exclusive advisory lock and return the
    descriptor; empty it (``truncate``) only once the lock is held.

    ``kind`` names the log in messages ("MCAP log", "Rerun recording").
    :class:`LogPathInUse` if another open file holds the lock; :class:`LogPathError` if the
    path cannot be opened (a directory, a read-only file system, no permission).
    """
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_CLOEXEC, 0o666)
    except OSError as error:
        raise LogPathError(f"{kind} {path}: cannot open it for writing: {describe_os_error(error)}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = lock_holder_pid(fd)
        os.close(fd)
        who = "an unknown process" if holder is None else \
            f"pid {holder}{' (this process)' if holder == os.getpid() else ''}"
        raise LogPathInUse(f"{kind} {path} is being written by {who}; "
                           "give this run another path or stop that writer") from None
    except OSError as error:      # a file system without flock: write unlocked
        if error.errno not in (errno.ENOLCK, errno.EOPNOTSUPP, errno.EINVAL):
            os.close(fd)
            raise LogPathError(f"{kind} {path}: cannot lock it: {describe_os_error(error)}") from None
    if truncate:
        try:
            os.ftruncate(fd, 0)
        except OSError as error:
            os.close(fd)
            raise LogPathError(f"{kind} {path}: cannot empty it: {describe_os_error(error)}") from None
    return fd


def room_left(path: Path) -> tuple[int, str]:
    """Bytes ``path`` may still grow by, and the errno a write past them gets: the free
    space of its file system for an unprivileged writer (``ENOSPC``) or, if smaller, what
    this process's file-size limit (RLIMIT_FSIZE) leaves (``EFBIG``)."""
    status = os.statvfs(path)
    room, error = status.f_bavail * status.f_frsize, "ENOSPC"
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    if limit != resource.RLIM_INFINITY and limit - path.stat().st_size < room:
        room, error = max(0, limit - path.stat().st_size), "EFBIG"
    return room, error


class FileSink:
    """Unbuffered, complete writes to an open descriptor (owned: ``close`` closes it and so
    releases its lock; a sink dropped unclosed closes it when collected).

    ``offset`` is the file position: the bytes written so far, partial writes included,
    also after ``write`` raised.
    """

    def __init__(self, fd: int) -> None:
        self._file = open(fd, "wb", buffering=0, closefd=True)   # noqa: SIM115 - closed by close()
        self.offset = self._file.tell()

    def write(self, data: bytes | bytearray | memoryview) -> int:
        """Write all of ``data`` (``OSError`` if the kernel refuses part of it); its length."""
        view = memoryview(data)
        while view:
            written = self._file.write(view)
            if written is None:          # pragma: no cover - only for non-blocking descriptors
                raise OSError(errno.EAGAIN, os.strerror(errno.EAGAIN))
            self.offset += written
            view = view[written:]
        return len(data)

    def tell(self) -> int:
        """The bytes written so far."""
        return self.offset

    def flush(self) -> None:
        """Nothing to flush (no buffer); present for the stream interface."""

    def fileno(self) -> int:
        """The descriptor."""
        return self._file.fileno()

    def truncate(self, size: int) -> None:
        """Cut the file to ``size`` bytes and write on from there."""
        os.ftruncate(self.fileno(), size)
        self.offset = self._file.seek(size)

    def sync(self) -> None:
        """``fsync``: the bytes written on the disk."""
        os.fsync(self.fileno())

    def close(self) -> None:
        """Close the descriptor (releases the lock); never raises."""
        try:
            self._file.close()
        except OSError:
            pass


@dataclass(frozen=True)
class LogWriteFailed:
    """A log whose write failed: logging stopped there, later log calls do nothing.

    ``reason`` is the errno's name and text (``ENOSPC (No space left on device)``);
    ``messages`` and ``bytes`` what the file holds as left (messages readable, file size;
    for a Rerun recording, samples);
    ``lost`` the messages logged but not in the file (the chunk being written, and any
    chunk given up to make room for the summary); ``finalised`` whether the summary and
    footer were written, so readers take the file as it is (otherwise ``log recover``
    rebuilds it from its complete chunks); ``unit`` what ``messages`` counts.
    """

    path: Path
    kind: str
    reason: str
    errno: str
    messages: int
    bytes: int
    lost: int
    finalised: bool
    unit: str = "messages"

    def __str__(self) -> str:
        state = ("the file is finalised (readable as it is)" if self.finalised else
                 f"the file is not finalised: `youbot-dynamics log recover {self.path}` rebuilds it")
        return (f"{self.kind} {self.path}: logging stopped on {self.reason} with {self.messages} {self.unit} "
                f"({self.bytes} bytes) in the file, {self.lost} lost; {state}")

    def key_values(self, prefix: str = "log") -> dict[str, str]:
        """The failure as /diagnostics key-value pairs (``<prefix>.path``, ``.error``, ...)."""
        values = {"path": str(self.path), "error": self.errno, "reason": self.reason,
                  "messages": str(self.messages), "bytes": str(self.bytes), "lost": str(self.lost),
                  "finalised": str(self.finalised).lower()}
        return {f"{prefix}.{key}": value for key, value in values.items()}
