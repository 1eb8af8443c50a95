"""What a test's child process does to run several console-script command lines in one
interpreter: each with its own argv, stdout and stderr files (file descriptors 1 and 2 pointed
at them), and the exit status the interpreter would give it.

Imported only in children (``sys.path`` gets this folder first; see :data:`IMPORT`), never by pytest.
"""

from __future__ import annotations

import os
import sys
import traceback
from pathlib import Path
from typing import Callable

#: The child's first line: this folder on its path, then this module's function.
IMPORT = f"import sys; sys.path.insert(0, {str(Path(__file__).resolve().parent)!r}); from console_child import run_as_console\n"


def run_as_console(call: Callable[[], object], argv: list[str], out: str, err: str) -> int:
    """Run ``call()`` with ``sys.argv = argv`` and fds 1 and 2 in the files ``out`` and ``err``;
    the exit status as the interpreter gives it (``SystemExit``'s code, a message printed to
    stderr as status 1, a traceback printed for any other exception, as status 1)."""
    kept = os.dup(1), os.dup(2)
    with open(out, "w") as stdout, open(err, "w") as stderr:
        os.dup2(stdout.fileno(), 1)
        os.dup2(stderr.fileno(), 2)
        sys.argv = list(argv)
        code = 0
        try:
            call()
        except SystemExit as done:
            if isinstance(done.code, str):
                print(done.code, file=sys.stderr)
            code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
        except BaseException:
            traceback.print_exc()
            code = 1
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(kept[0], 1)
        os.dup2(kept[1], 2)
        os.close(kept[0])
        os.close(kept[1])
    return code
