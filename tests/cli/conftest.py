"""Fixtures of the command-line tests: a command run in this process, shown as the console
script shows it."""

from __future__ import annotations

import contextlib
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import pytest


@dataclass
class Shown:
    """What a command did: its exit code, stdout and stderr (a process's, or what the console
    script would have shown of an in-process call)."""

    returncode: int
    stdout: str
    stderr: str


def run_here(args: list[str], env: Mapping[str, str | None] | None = None, cwd: Path | None = None) -> Shown:
    """``povagent ARGS`` in this process (typer's ``CliRunner``), ``env`` set (``None``: unset)
    and ``cwd`` entered for the call. A :class:`~povagent.errors.PovagentError` it raises is
    shown as :func:`povagent.cli.main` shows it (``error: <message>``, exit code 2); any other
    exception as a traceback (exit code 1), as an uncaught one would be. Whether the console
    script itself does so is a real process's to show (``python -m povagent.cli``)."""
    from typer.testing import CliRunner

    from povagent.cli import app
    from povagent.cli.process_exit import fast_exit_allowed
    from povagent.errors import PovagentError

    with contextlib.chdir(cwd) if cwd is not None else contextlib.nullcontext():
        result = CliRunner().invoke(app, args, env=dict(env or {}))
    fast_exit_allowed()  # only the console script ends its process early: nothing stays allowed here
    error = result.exception
    if isinstance(error, PovagentError):
        return Shown(2, result.stdout, result.stderr + f"error: {error}\n")
    if error is not None and not isinstance(error, SystemExit):
        return Shown(1, result.stdout, result.stderr + "".join(traceback.format_exception(error)))
    return Shown(result.exit_code, result.stdout, result.stderr)


@pytest.fixture
def console_here() -> Callable[..., Shown]:
    """:func:`run_here`: ``console_here(args, env=None, cwd=None) -> Shown``."""
    return run_here
