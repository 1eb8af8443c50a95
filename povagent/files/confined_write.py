"""Writing inside a folder the user named without following links someone else put there.

A run folder, a report folder or an export folder is untrusted once it exists: whoever prepared
it (a shared disk, an unpacked archive, a colleague's run copied over) may have planted a
symlink where povagent will write (``log.jsonl`` -> ``~/.bashrc``, ``rescored-official`` ->
``/etc``, ``report/report.html`` -> a file of yours). Opening such a path the ordinary way
appends to, truncates or replaces the file the link points at. This module opens targets the
way the kernel can hold to: the folder the user named is opened once (following links: the
user chose it), and every part below it is opened relative to its parent's descriptor with
``O_NOFOLLOW``, so a planted link is refused instead of followed, and nothing can be swapped
between a check and the open. A file appended to or cut in place must also have one name only
(a hard link, which an archive can carry, would write into its other name); a file written whole
is written aside and renamed over the target, which replaces a link rather than following it.

A refusal is a :class:`~povagent.errors.WriteTargetError`: one line naming the file and what is
wrong with it (a symbolic link, a folder where a file goes, a file where a folder goes). Other
OS errors (a full disk, a read-only mount) pass through unchanged for the callers that already
turn them into their own one-line message.

The cost is one ``openat`` per folder part when a target is opened (once per file, never per
row). The API, for every writer of povagent (run, rescore, report, summaries, exports):

- :class:`ConfinedFolder` ``(root, rel="")``: ``root`` (followed) then ``rel`` below it (made
  when missing, never followed); ``.sub(rel)``, ``.open_append(name)``, ``.open_update(name)``,
  ``.write_replace(name, data)``, ``.staged(name)`` (write aside, ``commit()`` renames),
  ``.unlink(name)``, ``.check_plain_file(name)`` (for a file another library opens by path),
  ``.path``, ``.descriptor`` (to read a file relative to the folder); a context manager that
  closes its descriptor;
- :func:`write_inside` ``(root, rel, data)``: one file written whole at ``root/rel``;
- :func:`open_inside` ``(root, rel, mode)``: ``"a"``/``"ab"`` to append, ``"r+b"`` to update.

This module must not decide where a dataset's paths lead (that is
:mod:`povagent.dataset.paths`), and it never follows a link below ``root``, even one leading
back inside: povagent itself never makes links in the folders it writes.
"""

from __future__ import annotations

import errno
import os
import stat
import threading
from pathlib import Path, PurePath, PurePosixPath
from typing import IO, Any

from povagent.errors import WriteTargetError

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_DIRECTORY = getattr(os, "O_DIRECTORY", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
#: Opening relative to a folder's descriptor is what makes the walk safe; without it (Windows)
#: each part is checked with ``lstat`` before use, which is the best that platform offers.
_DIR_FD = os.open in os.supports_dir_fd and bool(_NOFOLLOW)


def _parts(rel: str | PurePath) -> list[str]:
    """The names of ``rel``, which must stay below its root: no absolute path, no ``..``."""
    path = PurePosixPath(str(rel).replace(os.sep, "/")) if not isinstance(rel, PurePath) else PurePosixPath(*rel.parts)
    if path.is_absolute() or any(part == ".." for part in path.parts):
        raise ValueError(f"{rel!r} is not a path below the folder (absolute, or climbing with '..')")
    return [part for part in path.parts if part not in ("", ".")]


def _refusal(path: Path, exc: OSError, want: str) -> OSError | WriteTargetError:
    """The one-line refusal for an open of ``path`` that met a link or the wrong kind of entry."""
    try:
        st = os.lstat(path)
    except OSError:
        st = None
    if st is not None and stat.S_ISLNK(st.st_mode):
        return WriteTargetError(
            f"{path}: is a symbolic link, which povagent did not make; not followed and nothing written "
            f"(remove the link, or choose another folder)"
        )
    if exc.errno in (errno.ENOTDIR, errno.EEXIST) and want == "folder" and st is not None:
        return WriteTargetError(f"{path}: is a file where povagent keeps a folder; nothing written (move it away)")
    if exc.errno in (errno.EISDIR, errno.EPERM, errno.ENOTEMPTY) and want == "file" and st is not None and stat.S_ISDIR(st.st_mode):
        return WriteTargetError(f"{path}: is a folder where povagent writes a file; nothing written (move it away)")
    if exc.errno == errno.ELOOP:
        return WriteTargetError(f"{path}: leads through a symbolic link; not followed and nothing written")
    return exc


class ConfinedFolder:
    """A folder opened by descriptor: ``root`` as the user named it, then ``rel`` part by part.

    Each part of ``rel`` is made when missing (``create=True``) and opened with ``O_NOFOLLOW``:
    a symlink or a file in its place is a :class:`~povagent.errors.WriteTargetError` naming it.
    Files below are then opened relative to the folder's descriptor (see the module docstring).
    """

    def __init__(self, root: str | Path, rel: str | PurePath = "", *, create: bool = True) -> None:
        self.path = Path(root)
        self._fd: int | None = None
        if create:
            try:
                self.path.mkdir(parents=True, exist_ok=True)  # the folder the user named: theirs to place
            except FileExistsError as exc:
                raise _refusal(self.path, exc, "folder") from None
        try:
            self._fd = os.open(self.path, os.O_RDONLY | _DIRECTORY | _CLOEXEC) if _DIR_FD else None
        except NotADirectoryError as exc:
            raise _refusal(self.path, exc, "folder") from None
        try:
            for part in _parts(rel):
                self._enter(part, create)
        except BaseException:
            self.close()
            raise

    def _enter(self, name: str, create: bool) -> None:
        target = self.path / name
        if create:
            try:
                if self._fd is not None:
                    os.mkdir(name, 0o777, dir_fd=self._fd)
                else:
                    os.mkdir(target)
            except FileExistsError:
                pass  # a folder (ours, or the user's) or something else: the open below says which
            except OSError as exc:
                raise _refusal(target, exc, "folder") from None
        if self._fd is None:
            if target.is_symlink() or not target.is_dir():
                raise _refusal(target, OSError(errno.ENOTDIR, "not a folder"), "folder")
            self.path = target
            return
        try:
            fd = os.open(name, os.O_RDONLY | _DIRECTORY | _NOFOLLOW | _CLOEXEC, dir_fd=self._fd)
        except OSError as exc:
            raise _refusal(target, exc, "folder") from None
        os.close(self._fd)
        self._fd, self.path = fd, target

    @property
    def descriptor(self) -> int | None:
        """The folder's open descriptor, for opening a file relative to it (``dir_fd``); ``None``
        where the platform cannot (then :attr:`path` is all there is)."""
        return self._fd

    def sub(self, rel: str | PurePath, *, create: bool = True) -> ConfinedFolder:
        """The folder ``rel`` below this one, opened the same way (the caller closes it)."""
        inner = ConfinedFolder.__new__(ConfinedFolder)
        inner.path = self.path
        inner._fd = os.dup(self._fd) if self._fd is not None else None
        try:
            for part in _parts(rel):
                inner._enter(part, create)
        except BaseException:
            inner.close()
            raise
        return inner

    def _open(self, name: str, flags: int) -> int:
        if "/" in name or name in ("", ".", ".."):
            raise ValueError(f"{name!r} is not a file name")
        target = self.path / name
        try:
            if self._fd is not None:
                return os.open(name, flags | _NOFOLLOW | _CLOEXEC, 0o666, dir_fd=self._fd)
            if target.is_symlink():
                raise OSError(errno.ELOOP, "symbolic link", str(target))
            return os.open(target, flags | _CLOEXEC, 0o666)
        except OSError as exc:
            raise _refusal(target, exc, "file") from None

    def _single_name(self, fd: int, name: str) -> None:
        # A hard link has no mark of its own: one name is the only proof this file is the folder's.
        if os.fstat(fd).st_nlink > 1:
            os.close(fd)
            raise WriteTargetError(
                f"{self.path / name}: has other names (a hard link), so writing it would change a file "
                "elsewhere; nothing written (replace it with a copy, or choose another folder)"
            )

    def open_append(self, name: str, *, binary: bool = False, encoding: str = "utf-8") -> IO[Any]:
        """``name`` opened to append (made when missing), never through a link or a second name."""
        fd = self._open(name, os.O_WRONLY | os.O_APPEND | os.O_CREAT)
        self._single_name(fd, name)
        return os.fdopen(fd, "ab") if binary else os.fdopen(fd, "a", encoding=encoding)

    def open_update(self, name: str) -> IO[bytes]:
        """An existing ``name`` opened to read and cut in place (binary), never through a link."""
        fd = self._open(name, os.O_RDWR)
        self._single_name(fd, name)
        return os.fdopen(fd, "r+b")

    def staged(self, name: str, *, encoding: str | None = "utf-8", unique: bool = False) -> StagedFile:
        """A new ``name`` written aside (``name.tmp``) and renamed into place by ``commit()``.

        ``unique``: the temporary name also carries the process and thread (for writers that may
        write one name from several threads at once); a leftover of a kill then stays behind.
        """
        return StagedFile(self, name, encoding, unique)

    def write_replace(self, name: str, data: str | bytes, *, fsync: bool = False, unique: bool = False) -> None:
        """``name`` written whole: aside, then renamed over whatever stands there (a link included)."""
        with self.staged(name, encoding="utf-8" if isinstance(data, str) else None, unique=unique) as staged:
            staged.file.write(data)
            staged.commit(fsync=fsync)

    def check_plain_file(self, name: str) -> None:
        """Refuse ``name`` if it is a link, a file with a second name, or not a file (fine when
        missing): for a file another library opens by its path (SQLite). A check, not a
        descriptor: it cannot see a swap made after it, so use the openers above where you can."""
        target = self.path / name
        try:
            st = os.stat(name, dir_fd=self._fd, follow_symlinks=False) if self._fd is not None else os.lstat(target)
        except FileNotFoundError:
            return
        if stat.S_ISLNK(st.st_mode):
            raise _refusal(target, OSError(errno.ELOOP, "symbolic link"), "file")
        if stat.S_ISDIR(st.st_mode):
            raise _refusal(target, OSError(errno.EISDIR, "folder"), "file")
        if st.st_nlink > 1:
            raise WriteTargetError(
                f"{target}: has other names (a hard link), so writing it would change a file "
                "elsewhere; nothing written (replace it with a copy, or choose another folder)"
            )

    def unlink(self, name: str, *, missing_ok: bool = True) -> None:
        """Remove the entry ``name`` (a link itself, never what it points at); a folder is refused."""
        target = self.path / name
        try:
            if self._fd is not None:
                os.unlink(name, dir_fd=self._fd)
            else:
                os.unlink(target)
        except FileNotFoundError:
            if not missing_ok:
                raise
        except OSError as exc:
            raise _refusal(target, exc, "file") from None

    def rename(self, src: str, dst: str) -> None:
        """Rename ``src`` to ``dst`` inside this folder (``dst`` replaced, never followed)."""
        try:
            if self._fd is not None:
                os.rename(src, dst, src_dir_fd=self._fd, dst_dir_fd=self._fd)
            else:
                os.replace(self.path / src, self.path / dst)
        except OSError as exc:  # a folder standing where the file goes
            raise _refusal(self.path / dst, exc, "file") from None

    def fsync(self) -> None:
        """Make the folder's entries (a rename) durable."""
        fd = self._fd if self._fd is not None else os.open(self.path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            if fd != self._fd:
                os.close(fd)

    def close(self) -> None:
        """Let go of the folder's descriptor."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> ConfinedFolder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class StagedFile:
    """``name`` written under ``name.tmp`` (made new: a leftover, or a link planted there, is
    removed, never followed), put in place by :meth:`commit`; dropped when left uncommitted."""

    def __init__(self, folder: ConfinedFolder, name: str, encoding: str | None, unique: bool = False) -> None:
        self.folder = folder
        self.name = name
        self.tmp = f"{name}.{os.getpid()}.{threading.get_ident()}.tmp" if unique else name + ".tmp"
        self.path = folder.path / name
        if not unique:  # a leftover of a killed writer, or a link: only the entry goes
            folder.unlink(self.tmp)
        fd = folder._open(self.tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL)
        self.file: IO[Any] = os.fdopen(fd, "w", encoding=encoding) if encoding else os.fdopen(fd, "wb")
        self.committed = False

    def commit(self, *, fsync: bool = True) -> None:
        """Flush (and fsync) the staged bytes, then rename them over ``name`` in one move."""
        self.file.flush()
        if fsync:
            os.fsync(self.file.fileno())
        self.file.close()
        self.folder.rename(self.tmp, self.name)
        self.committed = True
        if fsync:
            self.folder.fsync()

    def __enter__(self) -> StagedFile:
        return self

    def __exit__(self, *exc: object) -> None:
        if not self.file.closed:
            try:
                self.file.close()
            except OSError:
                pass  # a full disk: the staged file is removed below either way
        if not self.committed:
            try:
                self.folder.unlink(self.tmp)
            except OSError:
                pass


def write_inside(root: str | Path, rel: str | PurePath, data: str | bytes, *, fsync: bool = False, unique: bool = False) -> Path:
    """Write ``root/rel`` whole (aside and renamed), its folders made and never followed below
    ``root``; ``unique`` as for :meth:`ConfinedFolder.staged`."""
    parts = _parts(rel)
    with ConfinedFolder(root, PurePosixPath(*parts[:-1]) if len(parts) > 1 else "") as folder:
        folder.write_replace(parts[-1], data, fsync=fsync, unique=unique)
        return folder.path / parts[-1]


def open_inside(root: str | Path, rel: str | PurePath, mode: str = "a", *, encoding: str = "utf-8") -> IO[Any]:
    """``root/rel`` opened to append (``"a"``, ``"ab"``) or to update (``"r+b"``), never through a link."""
    parts = _parts(rel)
    with ConfinedFolder(root, PurePosixPath(*parts[:-1]) if len(parts) > 1 else "") as folder:
        if mode in ("a", "ab"):
            return folder.open_append(parts[-1], binary=mode == "ab", encoding=encoding)
        if mode == "r+b":
            return folder.open_update(parts[-1])
        raise ValueError(f"mode {mode!r}: use write_inside to write a file whole")


__all__ = ["ConfinedFolder", "StagedFile", "open_inside", "write_inside"]
