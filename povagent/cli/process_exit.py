"""Ending the ``povagent`` process after ``run`` or ``sweep`` without the interpreter's teardown.

After a run that used litellm, an ordinary interpreter exit spends a second or more tearing
down: it clears thousands of modules' globals (litellm and openai load about 1,500 modules),
runs garbage collection over them and joins threads, and writes nothing while doing so. By
then every file of the run is written and closed: the runner closes ``log.jsonl``, the
response cache and the rows journal (``results.jsonl`` fsynced), and ``summary.json`` was
written atomically. So once ``run`` or ``sweep`` has printed its tables and chosen its exit
code, :func:`exit_now` flushes what Python still buffers (stdout, stderr, ``logging``
handlers) and ends the process with :func:`os._exit`: the same exit code, nothing lost, no
teardown.

Only the console script does this (:func:`povagent.cli.main`), and only after a command called
:func:`allow_fast_exit`: the library never ends a process, and a command run in-process (a
test's ``CliRunner``, a notebook) exits the ordinary way. ``atexit`` handlers are skipped:
povagent registers none, and litellm's (closing its HTTP clients' pools) release nothing the
operating system does not release with the process.
"""

from __future__ import annotations

import logging
import os
import sys
from typing import NoReturn

_allowed = False


def allow_fast_exit() -> None:
    """Called by ``run`` and ``sweep`` once their run folders are complete and closed."""
    global _allowed
    _allowed = True


def fast_exit_allowed() -> bool:
    """Whether the command that ran allowed :func:`exit_now` (and reset it)."""
    global _allowed
    allowed, _allowed = _allowed, False
    return allowed


def exit_code_of(code: object) -> int:
    """The process exit code ``sys.exit(code)`` would give (``None`` 0, an int itself, any
    other value printed to stderr and 1)."""
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    print(code, file=sys.stderr)
    return 1


def exit_now(code: object) -> NoReturn:
    """Flush stdout, stderr and every ``logging`` handler, then end the process at once."""
    status = exit_code_of(code)
    logging.shutdown()  # flushes and closes every handler
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more can reach it anyway
            pass
    os._exit(status)
