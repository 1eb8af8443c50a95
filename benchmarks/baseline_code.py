"""The code of an earlier commit, importable beside today's: how a benchmark times "before".

``baseline_checkout(ref)`` writes the ``povagent`` package of commit ``ref`` (``git archive``)
into a temporary folder, with the built-in plugins and prompts of that commit beside it under
their import names (``plugins/`` as ``povagent_plugins``, ``prompts/`` as ``povagent_prompts``),
and returns that folder; a subprocess run with it first on ``PYTHONPATH`` imports the old code
(today's plugins may need names the old package lacks) while the installed dependencies stay
the same. ``cpu_of(code, pythonpath)`` runs a snippet in such a subprocess and returns the CPU
seconds it prints. Benchmarks alternate the two subprocesses round by round, so both see the
same machine load.
"""

from __future__ import annotations

import io
import json
import os
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path
from typing import Any, Callable

REPO = Path(__file__).resolve().parent.parent


def baseline_checkout(ref: str, into: Path | None = None) -> Path:
    """A folder holding ``povagent/`` as it was at ``ref`` (a commit of this repository), with
    the built-in plugins and prompts of that commit under their import names
    (``povagent_plugins/``, ``povagent_prompts/``) when it had them. Where ``povagent`` is then
    imported from before and after is printed: the output shows the baseline is the old code."""
    into = into or Path(tempfile.mkdtemp(prefix="povagent-baseline-"))
    tree = subprocess.run(["git", "-C", str(REPO), "ls-tree", "--name-only", ref], check=True, capture_output=True,
                          text=True).stdout.split()  # fmt: skip
    folders = [f for f in ("povagent", "plugins", "prompts") if f in tree]
    archive = subprocess.run(["git", "-C", str(REPO), "archive", ref, *folders], check=True, capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(into, filter="data")
    for folder, name in (("plugins", "povagent_plugins"), ("prompts", "povagent_prompts")):
        if (into / folder).is_dir():
            (into / folder).rename(into / name)
    print(f"before: {imported_from(into)} (commit {ref}); after: {imported_from(None)}")
    return into


def env_with(pythonpath: Path | None) -> dict[str, str]:
    """This process's environment with ``pythonpath`` first on the import path (``None``: as is)."""
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(pythonpath), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def child_json(script: str, args: list[str], pythonpath: Path | None = None, env: dict[str, str] | None = None) -> dict:
    """Run ``script`` with ``args`` in a fresh interpreter (``pythonpath`` first on the import
    path, or the environment ``env``) and return the JSON object its last output line holds: a
    measurement taken in a process of its own, so its peak RSS is its own."""
    done = subprocess.run([sys.executable, script, *args], check=True, capture_output=True, text=True, env=env or env_with(pythonpath))
    return json.loads(done.stdout.strip().splitlines()[-1])


def peak_rss_mib() -> float:
    """This process's own peak RSS (``VmHWM``), in MiB: ``ru_maxrss`` would count a parent's too."""
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmHWM:")) / 1024


def cpu_seconds() -> float:
    """This process's CPU time so far, user + system (the machine is shared: wall time would
    measure the other jobs too)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def cpu_of(code: str, pythonpath: Path | None, timeout: float = 3600) -> dict[str, float]:
    """Run ``code`` in a fresh interpreter (``pythonpath`` first on the import path, or today's
    code when ``None``); ``code`` prints ``key=value`` lines, returned as floats."""
    env = env_with(pythonpath)
    # run outside the repository: ``python -c`` puts the working folder first on the path
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=tempfile.gettempdir(), check=True, capture_output=True, text=True, timeout=timeout
    ).stdout
    values = {}
    for line in out.splitlines():
        key, sep, value = line.partition("=")
        if sep:
            values[key.strip()] = float(value)
    return values


def imported_from(pythonpath: Path | None) -> str:
    """Where ``povagent`` is imported from with ``pythonpath`` (to show the baseline is the old code)."""
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    code = "import povagent, povagent_plugins, os; print(os.path.dirname(povagent.__file__), os.path.dirname(povagent_plugins.__file__))"
    return subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=tempfile.gettempdir(), check=True, capture_output=True, text=True
    ).stdout.strip()


def before_after_rounds(
    rounds: int, old: Path, measure: Callable[[str, Path | None, str], dict[str, Any]], after_round: Callable[[int, dict], None]
) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """``got[label][size]``: ``measure(label, pythonpath, size)`` of the ``small`` and ``large``
    sizes, ``before`` (``old``'s code) and ``after`` (today's), ``rounds`` times, the round's
    first label alternating (the machine is shared); ``after_round(r, got)`` prints a round."""
    got: dict[str, dict[str, list[dict[str, Any]]]] = {k: {"small": [], "large": []} for k in ("before", "after")}
    for r in range(rounds):
        order: tuple[tuple[str, Path | None], ...] = (("before", old), ("after", None)) if r % 2 == 0 else (("after", None), ("before", old))
        for label, path in order:
            for size in ("small", "large"):
                got[label][size].append(measure(label, path, size))
        after_round(r, got)
    return got


def peak_medians(by_size: dict[str, list[dict[str, Any]]]) -> dict[str, float]:
    """Medians over rounds of one label's measurements: peak(large) / peak(small) (``ratio``),
    each size's peak, and the large size's CPU seconds."""
    small, large = by_size["small"], by_size["large"]
    return {
        "ratio": statistics.median(b["peak_mib"] / s["peak_mib"] for s, b in zip(small, large)),
        "small": statistics.median(s["peak_mib"] for s in small),
        "large": statistics.median(b["peak_mib"] for b in large),
        "cpu_large": statistics.median(b["cpu_s"] for b in large),
    }
