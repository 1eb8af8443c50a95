"""What a Hub server says, checked before povagent builds a file path from it.

huggingface_hub writes the cache as ``<cache>/datasets--<owner>--<name>/`` with ``blobs/<etag>``,
``snapshots/<commit>/<file>``, ``refs/<revision>`` and ``trees/<commit>.json``: the commit id,
the ETag, the revision and every file name become parts of a path. A server (``HF_ENDPOINT``, a
mirror) chooses all of them but the revision, and a pipeline YAML (untrusted too) chooses the
revision. Each value is checked here against the one form it can honestly take; anything else
is a :class:`HubValueError` naming the value, quoted safely and cut short.

The rules:

* a commit id is exactly 40 lowercase hex digits (git's SHA-1 object id, what the Hub sends);
* a blob id (a git object id of a file) is 40 lowercase hex digits, an LFS file's sha256 is 64;
  one of them names the file's blob in ``blobs/``, as huggingface_hub names it from the ETag;
* a file size is a non-negative integer;
* a revision is what ``git check-ref-format --allow-onelevel`` accepts, at most
  :data:`MAX_REVISION` characters: ``/`` only between non-empty parts (``refs/pr/4``,
  ``release/v1``), no part starting with ``.`` or ending in ``.lock``, no ``..``, ``@{``, ``\\``,
  space, control character or any of ``~^:?*[``; not ``@``, not ending in ``.`` or ``/``. So no
  part can climb out of ``refs/``;
* a file name in the tree listing is a relative POSIX path of at most :data:`MAX_PATH`
  characters: parts that are not empty, ``.`` or ``..``, no ``\\``, no control character, not
  absolute, no Windows drive (``C:``).

This module only judges values; it reads and writes nothing (see :mod:`povagent.dataset.hub_transfer`).
"""

from __future__ import annotations

import re
import unicodedata

#: Longest revision accepted (git allows more; no real branch or tag comes near).
MAX_REVISION = 255
#: Longest repository file name accepted, and longest single part of it (a Linux file name).
MAX_PATH = 1024
MAX_PART = 255
#: How much of a refused value a message quotes.
SHOWN = 60

COMMIT_ID = re.compile(r"[0-9a-f]{40}")
BLOB_ID = COMMIT_ID
SHA256 = re.compile(r"[0-9a-f]{64}")
_REF_FORBIDDEN = set(" ~^:?*[\\")


class HubValueError(ValueError):
    """A value from a Hub server (or a revision from a config) that must not become a path part.

    ``what`` names the value (``repository commit id``, ``ETag of artifacts/x.png``...),
    ``value`` is the raw value, ``rule`` the form it should have.
    """

    def __init__(self, what: str, value: object, rule: str) -> None:
        self.what, self.value, self.rule = what, value, rule
        super().__init__(f"{what} {shown(value)} {rule}")


def shown(value: object, limit: int = SHOWN) -> str:
    """A value quoted for a one-line message: ``repr`` (control characters escaped), cut short."""
    text = value if isinstance(value, str) else repr(value)
    cut = text[:limit]
    quoted = repr(cut)
    return quoted + (f"... ({len(text)} characters)" if len(text) > limit else "")


def _has_control(text: str) -> bool:
    return any(unicodedata.category(ch) in ("Cc", "Cf", "Zl", "Zp") for ch in text)


def check_commit_id(value: object, what: str = "repository commit id") -> str:
    """``value`` if it is a commit id (40 lowercase hex digits), else :class:`HubValueError`."""
    if isinstance(value, str) and COMMIT_ID.fullmatch(value):
        return value
    raise HubValueError(what, value, "is not a commit id (40 lowercase hex digits)")


def check_blob_name(value: object, what: str) -> str:
    """``value`` if it is a git blob id (40 hex) or a sha256 (64 hex): a safe ``blobs/`` file name."""
    if isinstance(value, str) and (BLOB_ID.fullmatch(value) or SHA256.fullmatch(value)):
        return value
    raise HubValueError(what, value, "is not a git object id (40 lowercase hex digits) or a sha256 (64)")


def check_sha256(value: object, what: str) -> str:
    """``value`` if it is a sha256 (64 lowercase hex digits)."""
    if isinstance(value, str) and SHA256.fullmatch(value):
        return value
    raise HubValueError(what, value, "is not a sha256 (64 lowercase hex digits)")


def check_size(value: object, what: str) -> int:
    """``value`` if it is a non-negative integer (a file size in bytes)."""
    if isinstance(value, int) and not isinstance(value, bool) and value >= 0:
        return value
    raise HubValueError(what, value, "is not a size in bytes (a non-negative integer)")


def check_revision(value: object, what: str = "revision") -> str:
    """``value`` if it is a branch, tag or commit name git accepts (see the module docstring)."""
    rule = "is not a branch, tag or commit name (see git check-ref-format: no '..', no part starting with '.')"
    if not isinstance(value, str) or not value or len(value) > MAX_REVISION:
        raise HubValueError(what, value, f"{rule}; 1 to {MAX_REVISION} characters")
    bad = (
        _has_control(value)
        or any(ch in _REF_FORBIDDEN for ch in value)
        or ".." in value
        or "@{" in value
        or value == "@"
        or value.endswith((".", "/"))
        or value.startswith("/")
        or any(not part or part.startswith(".") or part.endswith(".lock") for part in value.split("/"))
    )
    if bad:
        raise HubValueError(what, value, rule)
    return value


def check_repo_path(value: object, what: str = "file name in the tree listing") -> str:
    """``value`` if it is a relative POSIX path that stays inside the snapshot folder."""
    rule = "is not a relative path inside the repository (no '..', '.', empty part, '\\', drive or absolute path)"
    if not isinstance(value, str) or not value or len(value) > MAX_PATH:
        raise HubValueError(what, value, f"{rule}; 1 to {MAX_PATH} characters")
    parts = value.split("/")
    bad = (
        value.startswith("/")
        or "\\" in value
        or _has_control(value)
        or re.match(r"[A-Za-z]:", value) is not None
        or any(part in ("", ".", "..") or len(part) > MAX_PART for part in parts)
    )
    if bad:
        raise HubValueError(what, value, rule)
    return value
