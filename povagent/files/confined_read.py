"""Reading a file from a folder someone else may have made: regular files only, never too much.

A checkpoint folder, a dataset, a run folder being resumed, a views store: whoever made it may
have put a FIFO where a file goes (an ordinary ``open`` then waits for a writer forever, and no
signal handler runs while a thread sits in that call), a link to ``/dev/zero`` or ``/dev/urandom``
(an ordinary ``read()`` then fills memory until the process dies), or a file of many GiB where a
few KiB are expected. Every such read in povagent goes through this module:

- the file is opened with ``O_NONBLOCK`` (opening a FIFO returns at once instead of waiting)
  and checked with ``fstat`` on that descriptor: anything but a regular file (a FIFO, a device,
  a socket, a folder) is refused before a byte is read, and nothing can be swapped between the
  check and the read;
- a whole-file read names its bound: a file larger than it is refused from its size, and no
  more than the bound plus one byte is ever read (a file growing meanwhile is refused too);
- :func:`read_inside` also refuses a symbolic link anywhere below the folder the user named,
  for folders povagent made itself and never fills with links (a run folder, its views store);
  :func:`read_regular` follows links, for folders whose links are part of the format (a Hugging
  Face cache snapshot links each file to a blob) and for paths whose place was already checked
  (a dataset's paths, :mod:`povagent.dataset.paths`).

A refusal is a :class:`~povagent.errors.ReadTargetError`: one line naming the file, what it is,
and the bound. A missing file is :class:`FileNotFoundError` as usual, so callers keep their own
"not found" messages; other OS errors pass through unchanged.

The API, for every reader of untrusted files:

- :func:`read_regular` ``(path, max_bytes, what=...)``: the bytes of a regular file;
- :func:`open_regular` ``(path, what=...)``: a regular file opened for reading in binary, for a
  reader that streams (a journal read line by line keeps its own bound per line);
- :func:`read_inside` ``(root, rel, max_bytes, what=...)``: like :func:`read_regular`, with no
  link followed below ``root``;
- :func:`read_at` ``(folder, name, max_bytes, what=...)``: a file of a folder povagent holds open
  (a :class:`~povagent.files.confined_write.ConfinedFolder`), read through the folder's descriptor,
  so the folder cannot be swapped for a link between its check and the read;
- :func:`open_at` ``(folder, name, what=...)``: the same file open for a reader that streams it
  (a frame cache entry, read a chunk at a time; the caller bounds what it reads);
- :func:`check_regular` ``(path, max_bytes, what=...)``: the size of a file another library opens
  by path (``transformers``, ``safetensors``), refused as :func:`read_regular` would refuse it.

This module must not decide where a path may lead (that is :mod:`povagent.dataset.paths`), and
it never writes (that is :mod:`povagent.files.confined_write`).
"""

from __future__ import annotations

import errno
import io
import os
import stat
from pathlib import Path, PurePosixPath
from typing import Any

from povagent.errors import ReadTargetError

_NONBLOCK = getattr(os, "O_NONBLOCK", 0)
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_DIRECTORY = getattr(os, "O_DIRECTORY", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_READ = os.O_RDONLY | _NONBLOCK | _CLOEXEC | getattr(os, "O_BINARY", 0)

#: Bytes per MiB, for messages.
MIB = 1 << 20


#: The most a document read whole may hold (a house record, an index, a summary, a marker).
MAX_DOCUMENT_BYTES = 64 * MIB
#: The most an image file read whole may hold (a frame, an observer view, a rendered view).
MAX_IMAGE_FILE_BYTES = 256 * MIB


def _refusal(path: str | Path, what: str, reason: str) -> ReadTargetError:
    """The one-line refusal; ``reason`` (without the path) is kept for callers that name the
    file their own way (a dataset's problems list, by file and field)."""
    exc = ReadTargetError(f"{path}: {what} {reason}; not read")
    exc.reason = f"{what} {reason}"
    return exc


def _size_text(n: int) -> str:
    if n < MIB:
        return f"{n} bytes"
    return f"{n // MIB} MiB" if n % MIB == 0 else f"{n / MIB:.1f} MiB"


def _kind(mode: int) -> str:
    """What a non-regular entry is, in the words a message uses."""
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISDIR(mode):
        return "a folder"
    return "not a regular file"


def _checked(fd: int, path: str | Path, what: str, max_bytes: int | None) -> int:
    """The size of the regular file open as ``fd``; anything else (or a file over ``max_bytes``)
    closes ``fd`` and raises :class:`ReadTargetError`."""
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise _refusal(path, what, f"is {_kind(st.st_mode)}, not a regular file")
    if max_bytes is not None and st.st_size > max_bytes:
        os.close(fd)
        raise _refusal(path, what, f"holds {_size_text(st.st_size)}, more than the {_size_text(max_bytes)} it may hold")
    return st.st_size


def _read_all(fd: int, path: str | Path, what: str, max_bytes: int) -> bytes:
    with os.fdopen(fd, "rb") as fh:
        data = fh.read(max_bytes + 1)
    if len(data) > max_bytes:  # grew since fstat: the bound holds for what is read, not what was seen
        raise _refusal(path, what, f"grew past the {_size_text(max_bytes)} it may hold while being read")
    return data


def _open_following(path: str | Path) -> int:
    return os.open(path, _READ)


def read_regular(path: str | Path, max_bytes: int, *, what: str = "file") -> bytes:
    """The bytes of the regular file at ``path`` (links followed), at most ``max_bytes``.

    A FIFO, a device, a socket or a folder there, or a file larger than ``max_bytes``, is a
    :class:`ReadTargetError` naming it (``what`` says what the file was expected to be).
    """
    fd = _open_following(path)
    _checked(fd, path, what, max_bytes)
    return _read_all(fd, path, what, max_bytes)


def open_regular(path: str | Path, *, what: str = "file") -> io.BufferedReader:
    """The regular file at ``path`` (links followed) open for reading in binary; anything else
    is a :class:`ReadTargetError`. The caller bounds what it reads (a line at a time, say)."""
    fd = _open_following(path)
    _checked(fd, path, what, None)
    os.set_blocking(fd, True)  # a regular file never blocks; later reads behave as usual
    return os.fdopen(fd, "rb")


def check_regular(path: str | Path, max_bytes: int | None = None, *, what: str = "file") -> int:
    """The size of the regular file at ``path`` (links followed), for a file another library
    opens by its path; refused as :func:`read_regular` refuses it. (The library opens it again:
    a file swapped between the check and its open is not caught here.)"""
    fd = _open_following(path)
    size = _checked(fd, path, what, max_bytes)
    os.close(fd)
    return size


def _parts(rel: str | PurePosixPath) -> list[str]:
    path = PurePosixPath(str(rel).replace(os.sep, "/"))
    if path.is_absolute() or ".." in path.parts:
        raise ValueError(f"{rel!r} is not a path below the folder (absolute, or climbing with '..')")
    return [p for p in path.parts if p not in ("", ".")]


def _open_inside(root: str | Path, rel: str | PurePosixPath, what: str) -> int:
    """``root/rel`` opened for reading, ``root`` followed and no link below it."""
    parts = _parts(rel)
    if not parts:
        raise ValueError(f"{rel!r} names no file below {root}")
    if not (os.open in os.supports_dir_fd and _NOFOLLOW):  # no descriptor walk here: check each part
        here = Path(root)
        for part in parts:
            here = here / part
            if here.is_symlink():
                raise _refusal(here, what, "leads through a symbolic link, which povagent did not make")
        return os.open(here, _READ)
    folder = os.open(root, os.O_RDONLY | _DIRECTORY | _CLOEXEC)
    here = Path(root)
    try:
        for part in parts[:-1]:
            here = here / part
            try:
                inner = os.open(part, os.O_RDONLY | _DIRECTORY | _NOFOLLOW | _CLOEXEC, dir_fd=folder)
            except OSError as exc:
                raise _link_refusal(here, exc, what) from None
            os.close(folder)
            folder = inner
        here = here / parts[-1]
        try:
            return os.open(parts[-1], _READ | _NOFOLLOW, dir_fd=folder)
        except OSError as exc:
            raise _link_refusal(here, exc, what) from None
    finally:
        os.close(folder)


def _link_refusal(path: Path, exc: OSError, what: str) -> OSError | ReadTargetError:
    if exc.errno in (errno.ELOOP, errno.ENOTDIR) and path.is_symlink():
        return _refusal(path, what, "leads through a symbolic link, which povagent did not make")
    return exc


def read_inside(root: str | Path, rel: str | PurePosixPath, max_bytes: int, *, what: str = "file") -> bytes:
    """The bytes of the regular file ``root/rel``, at most ``max_bytes``, following ``root``
    (the user named it) and no link below it; refusals as in :func:`read_regular`."""
    path = Path(root) / str(rel)
    fd = _open_inside(root, rel, what)
    _checked(fd, path, what, max_bytes)
    return _read_all(fd, path, what, max_bytes)


def open_at(folder: Any, name: str, *, what: str = "file") -> io.BufferedReader:
    """The regular file ``name`` in ``folder`` (a :class:`~povagent.files.confined_write.ConfinedFolder`)
    open for reading in binary, not following a link; refusals as in :func:`read_at`. The caller
    bounds what it reads. Without a descriptor it opens the path below the folder, no link followed."""
    path = Path(folder.path) / name
    try:
        fd = os.open(name, _READ | _NOFOLLOW, dir_fd=folder.descriptor) if folder.descriptor is not None else _open_inside(folder.path, name, what)
    except OSError as exc:
        raise _link_refusal(path, exc, what) from None
    _checked(fd, path, what, None)
    os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")


def read_at(folder: Any, name: str, max_bytes: int, *, what: str = "file") -> bytes:
    """The bytes of the regular file ``name`` in ``folder`` (a
    :class:`~povagent.files.confined_write.ConfinedFolder`: its open ``descriptor`` and its
    ``path``), not following a link, at most ``max_bytes``; refusals as in :func:`read_inside`.
    Without a descriptor (a platform with no ``dir_fd``) it is :func:`read_inside` of the path."""
    if folder.descriptor is None:
        return read_inside(folder.path, name, max_bytes, what=what)
    path = Path(folder.path) / name
    try:
        fd = os.open(name, _READ | _NOFOLLOW, dir_fd=folder.descriptor)
    except OSError as exc:
        raise _link_refusal(path, exc, what) from None
    _checked(fd, path, what, max_bytes)
    return _read_all(fd, path, what, max_bytes)
