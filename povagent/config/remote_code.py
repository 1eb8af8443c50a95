"""Whether a checkpoint's own Python code may run: the person running povagent decides, never a file.

A Hugging Face checkpoint may name Python files in its ``config.json`` (``auto_map``); loading
it with ``trust_remote_code=True`` imports them, with your rights. Like a plugin or a cluster
scheduler, that is code, so only what you type chooses it: ``--trust-remote-code`` on the
command line (``run``, ``sweep``, ``ros-node``, ``ros-replay``), or ``trust_remote_code=True``
given to the Python call (:func:`povagent.run.runner.run_pipeline`,
:func:`povagent.run.sweep.run_sweep`, :class:`povagent.agent.GroundingAgent` and its
``from_pipeline``). A pipeline or sweep YAML (untrusted input), a mapping given as a pipeline,
and a model profile cannot: ``trust_remote_code: true`` among a pipeline's options is refused
when the config is read (:func:`check_remote_code_options`), and a profile whose checkpoint
needs its code only says so (:func:`needs_the_flag`).

With the grant, a checkpoint fetched from the Hub runs the code of the revision it is loaded at,
and a branch or a pull-request ref (``refs/pr/N``, which anyone can open) is whatever was pushed
last: a ``revision`` a pipeline names must then be a commit hash (:func:`check_pinned_revision`).

How the grant reaches a backend: the calls above hold it in a context variable while they make
their backend (:func:`remote_code_granted`), and a backend that loads checkpoints asks
:func:`remote_code_allowed` when it is made. Nothing else sets it, so a plugin option or a file
cannot, and it does not outlive the call that granted it.

This module decides nothing else about checkpoints (their files: the backend's own checks) and
never imports ``transformers``.
"""

from __future__ import annotations

import contextlib
import re
from contextvars import ContextVar
from typing import Any, Iterator, Mapping

from povagent.config.quoting import Loc, dotted
from povagent.config.yaml_reader import ConfigSource
from povagent.errors import ConfigError

#: The option name ``transformers`` (and every backend following it) gives the permission.
REMOTE_CODE_OPTION = "trust_remote_code"
#: The command-line flag that grants it.
REMOTE_CODE_FLAG = "--trust-remote-code"
#: A commit of a git repository (what the Hub resolves every revision to).
COMMIT_HASH = re.compile(r"^[0-9a-f]{40}$")

#: Why a file may not grant it, and how the user does.
FROM_A_FILE = (
    f"a pipeline cannot turn on a checkpoint's own Python code; remove this line and pass {REMOTE_CODE_FLAG} "
    "on the command line (or trust_remote_code=True to the Python call) to run code you trust"
)

_granted: ContextVar[bool] = ContextVar("povagent_remote_code_granted", default=False)


@contextlib.contextmanager
def remote_code_granted(granted: bool = True) -> Iterator[None]:
    """Within this block, backends made may run their checkpoint's own code (``granted``)."""
    token = _granted.set(granted)
    try:
        yield
    finally:
        _granted.reset(token)


def remote_code_allowed() -> bool:
    """Whether the command line or the Python call granted remote code to the backend being made."""
    return _granted.get()


def is_commit_hash(revision: str | None) -> bool:
    """Whether ``revision`` names one commit (40 lowercase hex digits), not a branch or a ref."""
    return isinstance(revision, str) and COMMIT_HASH.match(revision) is not None


def needs_the_flag(what: str, revision: str | None) -> str:
    """The one line for a checkpoint or profile that needs its own code when none was granted."""
    pinned = f"revision {revision}" if revision else "no pinned revision"
    return f"{what} runs the checkpoint's own Python code ({pinned}): pass {REMOTE_CODE_FLAG} to run it, if you trust that code"


def check_pinned_revision(model: str, revision: str | None, *, hub_id: bool) -> None:
    """With remote code granted, refuse a Hub checkpoint whose ``revision`` names a branch or a
    ref rather than a commit. No revision is the repository's default branch: its owner's
    code, which the user chose to trust by naming the repository and passing the flag."""
    if not hub_id or revision is None:
        return  # a folder runs the code it holds: the user named it
    if not is_commit_hash(revision):
        raise ConfigError(
            f"backend option 'revision': {revision[:80]!r} is a branch or a ref, not a commit hash; with "
            f"{REMOTE_CODE_FLAG} the code must be pinned to the commit you checked (40 hex digits)"
        )


def check_remote_code_options(options: Any, loc: Loc, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """A ``trust_remote_code`` set to anything but false among ``options`` (at any depth) is a
    problem at its line: a config never grants remote code (see the module docstring)."""
    stack: list[tuple[Loc, Any]] = [(loc, options)]
    while stack:
        here, value = stack.pop()
        if isinstance(value, Mapping):
            for k, v in value.items():
                if k == REMOTE_CODE_OPTION and v is not False and v is not None:
                    problems.append(f"{source.where(prefix + here + (k,))}: {dotted(here + (k,))}: {FROM_A_FILE}")
                else:
                    stack.append((here + (k,), v))
        elif isinstance(value, list):
            stack.extend((here + (i,), v) for i, v in enumerate(value))
