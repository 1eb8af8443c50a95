"""``povagent`` commands as processes of their own, forked from one interpreter that imported
povagent and its built-in plugins once.

A fresh ``python -m povagent.cli`` spends most of a second importing (and, with bytecode writes
off, compiling) povagent and its plugins before the command starts; the tests here that run
the command as a process are about what the command then does: its exit code, what it prints,
what it writes, how it ends on a signal. :class:`CommandForks` starts one interpreter that
imports all of that and waits; each command is a child forked from it, which runs
``povagent.cli`` as ``python -m`` does, with its own working folder, environment, stdin from
``/dev/null``, stdout and stderr in files of its own, and ends as that process would (its exit
code, or the signal that killed it). Nothing runs in the waiting interpreter but imports: each
child starts from the same state, whatever ran before.

A test that is about a fresh interpreter (what start-up imports, litellm loading in the
background) starts one of its own instead.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

#: The waiting interpreter: imports, then one child per request line (JSON) on stdin, answering
#: ``{"id": ..., "pid": ...}`` when the child starts and ``{"id": ..., "returncode": ...}`` when it
#: has ended (children run side by side: one a test left running holds up no other). At the end of
#: its input, it kills the children still running.
SERVER = r"""
import importlib, json, os, pkgutil, resource, runpy, select, signal, subprocess, sys

import povagent_plugins

for name in ("povagent.cli", "povagent.config.pipeline", "povagent.run.runner", "povagent.run.sweep",
             "povagent.run.rescore", "povagent.default_plugins", "povagent.active", "povagent.annotate",
             "jsonschema", "PIL.ImageDraw", "statistics"):
    importlib.import_module(name)
for info in pkgutil.walk_packages(povagent_plugins.__path__, "povagent_plugins."):
    importlib.import_module(info.name)


def answer(**fields):
    os.write(answers, json.dumps(fields).encode() + b"\n")


def reap(children, block):
    while children:
        pid, status = os.waitpid(-1, 0 if block else os.WNOHANG)
        if pid == 0:
            return
        answer(id=children.pop(pid), returncode=os.waitstatus_to_exitcode(status))


answers = os.dup(1)
answer(ready=True)
requests = sys.stdin.buffer.raw
pending = b""
children = {}
while True:
    # a wait of 20 ms at most while a child runs: its end is answered that soon
    if select.select([requests], [], [], 0.02 if children else None)[0]:
        chunk = os.read(requests.fileno(), 65536)
        if not chunk:
            break
        pending += chunk
    while b"\n" in pending:
        line, pending = pending.split(b"\n", 1)
        request = json.loads(line)
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:
            # the child: the command's process, as `python -m povagent.cli ARGS` would start it
            os.close(answers)
            os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
            os.dup2(os.open(request["stdout"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), 1)
            os.dup2(os.open(request["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), 2)
            os.chdir(request["cwd"])
            os.environ.clear()
            os.environ.update(request["env"])
            if request["env"].get("PYTHONUNBUFFERED"):
                sys.stdout.reconfigure(write_through=True)
                sys.stderr.reconfigure(write_through=True)
            if request["fsize"] is not None:
                resource.setrlimit(resource.RLIMIT_FSIZE, (request["fsize"], request["fsize"]))
            for command in request["before"]:
                subprocess.run(["sh", "-c", command], check=True)
            sys.argv = ["povagent", *request["args"]]
            runpy.run_module("povagent.cli", run_name="__main__", alter_sys=True)
            sys.exit(0)  # the module ran to its end: what the interpreter then does
        children[pid] = request["id"]
        answer(id=request["id"], pid=pid)
    reap(children, block=False)
for pid in children:
    os.kill(pid, signal.SIGKILL)
reap(children, block=True)
"""


class CommandForks:
    """The waiting interpreter, started by ``prefix + [python]`` (e.g. ``unshare -rm``: every
    child then runs in that namespace), its children's output kept under ``folder``."""

    def __init__(self, folder: Path, env: dict[str, str], prefix: list[str] | None = None) -> None:
        self.folder = folder
        self.count = 0
        self.pending = b""
        self.answers: dict[tuple[int, str], int] = {}
        folder.mkdir(parents=True, exist_ok=True)
        self.log = folder / "server-stderr.txt"
        with open(self.log, "wb") as log:
            self.proc = subprocess.Popen([*(prefix or []), sys.executable, "-c", SERVER], stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, stderr=log, env=env)  # fmt: skip
        assert self.answer(0, "ready", 120), self.log.read_text()[-3000:]

    def answer(self, command: int, key: str, timeout: float) -> int | None:
        """The server's answer ``key`` about ``command`` (its ``pid`` or ``returncode``), or None
        when none came within ``timeout`` seconds; answers about other commands are kept."""
        assert self.proc.stdout is not None
        deadline = time.monotonic() + timeout
        while (command, key) not in self.answers:
            if b"\n" in self.pending:
                line, self.pending = self.pending.split(b"\n", 1)
                fields = json.loads(line)
                number = fields.pop("id", 0)
                ((name, value),) = fields.items()
                self.answers[(number, name)] = value
                continue
            ready, _, _ = select.select([self.proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
            if not ready:
                return None
            chunk = os.read(self.proc.stdout.fileno(), 4096)
            assert chunk, f"the command server ended: {self.log.read_text()[-3000:]}"
            self.pending += chunk
        return self.answers.pop((command, key))

    def start(self, *args: object, cwd: Path, env: dict[str, str] | None = None, fsize: int | None = None,
              before: list[str] | None = None) -> Command:  # fmt: skip
        """``povagent ARGS`` started in ``cwd`` with ``env`` (this process's if None), under a
        file-size limit of ``fsize`` bytes, after the shell commands ``before`` ran in its process."""
        self.count += 1
        out, err = self.folder / f"{self.count}.stdout", self.folder / f"{self.count}.stderr"
        request = {"id": self.count, "args": [str(a) for a in args], "cwd": str(cwd), "env": dict(os.environ) if env is None else env,
                   "fsize": fsize, "before": before or [], "stdout": str(out), "stderr": str(err)}  # fmt: skip
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(request).encode() + b"\n")
        self.proc.stdin.flush()
        pid = self.answer(self.count, "pid", 60)
        assert pid is not None, "the command did not start"
        return Command(self, self.count, pid, out, err)

    def run(self, *args: object, cwd: Path, timeout: float = 150, **options) -> subprocess.CompletedProcess[str]:
        """``povagent ARGS`` run to its end: what ``subprocess.run(..., capture_output=True, text=True)`` returns."""
        command = self.start(*args, cwd=cwd, **options)
        returncode = command.wait(timeout)
        return subprocess.CompletedProcess(["povagent", *map(str, args)], returncode, command.stdout(), command.stderr())

    def close(self) -> None:
        """Stop the server (it kills the children still running) and wait for it."""
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=30)


class Command:
    """A started command: its ``pid``, ``poll()``, ``wait()``, ``send_signal()`` as a
    ``subprocess.Popen``'s, and its output once it has ended."""

    def __init__(self, server: CommandForks, number: int, pid: int, out: Path, err: Path) -> None:
        self.server, self.number, self.pid, self.out, self.err = server, number, pid, out, err
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None:
            self.returncode = self.server.answer(self.number, "returncode", 0)
        return self.returncode

    def wait(self, timeout: float) -> int:
        if self.returncode is None:
            self.returncode = self.server.answer(self.number, "returncode", timeout)
            if self.returncode is None:
                self.send_signal(signal.SIGKILL)  # as subprocess.run's timeout does
                self.returncode = self.server.answer(self.number, "returncode", 30)
                raise subprocess.TimeoutExpired(["povagent", str(self.pid)], timeout)
        return self.returncode

    def send_signal(self, sig: int) -> None:
        # as Popen's: only while its end is not known here, and an end just reaped (the server
        # answers it at once) is no error
        if self.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, sig)

    def stdout(self) -> str:
        return self.out.read_text()

    def stderr(self) -> str:
        return self.err.read_text()
