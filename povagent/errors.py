"""The exceptions a user may see.

Each carries a message that says what went wrong and what to do. Anything else raised inside
povagent is a bug and keeps its traceback.
"""

from __future__ import annotations

import errno
from collections.abc import Sequence


class PovagentError(Exception):
    """Base class of every error povagent reports to a user without a traceback."""


class DatasetError(PovagentError):
    """A dataset folder or file is missing or malformed (the message names file and field)."""


class ConfigError(PovagentError):
    """A pipeline or sweep YAML is malformed (the message names file, line and field)."""


class PluginError(PovagentError):
    """A plugin failed to load, is unknown, or registers a name another plugin already owns."""


class PredictionsError(PovagentError):
    """A predictions or results file cannot be read."""


class ResultsError(PovagentError):
    """A run's results file cannot be written (a full disk, a lost mount); rows already written stay."""

    @classmethod
    def cannot_write(cls, path: object, exc: BaseException) -> ResultsError:
        """The one-line stop for a write that failed: ``path`` and why, and how to resume."""
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else f"{type(exc).__name__}: {exc}"
        return cls(
            f"{path}: cannot write ({why}); the rows already written are kept: free space (or fix "
            f"the folder) and run the same command again to resume"
        )


class WriteTargetError(PovagentError):
    """A place povagent writes is a symbolic link, a second name of another file, or the wrong
    kind of entry (a file where a folder goes, or the reverse): refused, never followed
    (see :mod:`povagent.files.confined_write`)."""


class OutputFileError(PovagentError):
    """A file named on the command line for output (``--out FILE``) cannot be written there: an
    empty name, a folder in its place, a place that refuses the write."""


class ReadTargetError(PovagentError):
    """A file povagent reads from a folder someone else may have made is not a regular file (a
    pipe, a device, a socket, a folder), is larger than what it may hold, or leads through a
    link where none belongs: refused before it is read, never waited on
    (see :mod:`povagent.files.confined_read`). ``reason`` is the message without the file's name."""

    reason: str = ""


#: ``errno`` values of a write that found no room: a full disk, a full quota, a file size limit.
NO_ROOM_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})


#: ``errno`` values of a file system refusing a path or a write (beside a full one), as opposed
#: to a network connection's failures, which are OSErrors too.
FILE_SYSTEM_ERRNOS = NO_ROOM_ERRNOS | {
    errno.EROFS, errno.EACCES, errno.EPERM, errno.EIO, errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.ENAMETOOLONG, errno.ELOOP,
}


def is_file_system_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a file or folder that could not be written or read (a full disk, a
    read-only mount, a missing folder), not a lost connection."""
    return isinstance(exc, OSError) and (exc.filename is not None or exc.errno in FILE_SYSTEM_ERRNOS)


class GenerationError(PovagentError):
    """Some houses of a generation failed; the others are on disk. ``failures`` lists
    (index, seed, error) of each failed house; running the same command again redoes only them."""

    def __init__(self, message: str, failures: Sequence[object] = ()) -> None:
        super().__init__(message)
        self.failures = list(failures)

    @classmethod
    def cannot_write(cls, out: object, exc: OSError) -> GenerationError:
        """The one-line stop of a generation whose output folder refused a write."""
        why = exc.strerror or f"{type(exc).__name__}: {exc}"
        where = exc.filename if exc.filename is not None else out
        return cls(
            f"{where}: cannot write ({why}); houses already complete in {out} are kept: free space or choose a "
            "writable --out, then run the same command again"
        )


class ClusterError(PovagentError):
    """The cluster cannot be used: Dask is not installed, a bad ``--cluster`` value, no scheduler."""


class BackendError(PovagentError):
    """A model backend failed permanently (after retries, or on a non-transient error)."""


class GroundingError(PovagentError):
    """Base class of the errors :class:`povagent.agent.grounding_agent.GroundingAgent` raises to robot apps."""


class NoAnswerError(GroundingError):
    """The model gave no answer: every attempt failed or timed out."""


class UnparseableAnswerError(GroundingError):
    """The model answered, but no point could be read from its answer.

    ``raw_answer`` is the model's text and ``parsed`` the typed parse (a
    :class:`povagent.answers.spec.ParsedAnswer`), so a robot app can log it or ask again.
    """

    def __init__(self, message: str, raw_answer: str | None = None, parsed: object | None = None) -> None:
        super().__init__(message)
        self.raw_answer = raw_answer
        self.parsed = parsed


class BadInputError(GroundingError):
    """The agent's input is unusable: no frames, an unreadable image, a wrong camera."""
