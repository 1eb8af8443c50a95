"""What ``--cluster`` (or a YAML's ``cluster:`` key) names, read without importing Dask.

A configuration value like any other, so it sits with the configuration: checking a config never
imports :mod:`povagent.cluster`, which only ``--cluster`` loads. Two forms: ``local:N`` starts a
Dask ``LocalCluster`` of N worker processes on this machine; ``tcp://HOST:PORT`` (or ``tls://``)
connects to a scheduler that is already running. Parsing is pure so a config can be checked, and
a bad value refused, before anything starts.

Who may name which form: a scheduler exchanges pickles with this process both ways, so whoever
runs it runs code here. An address therefore comes only from the command line or the library
call; a YAML file (untrusted input) may ask for ``local:N`` at most (:func:`yaml_cluster_spec`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

from povagent.errors import ClusterError

#: Schemes of a running scheduler's address that Dask's comm layer speaks.
SCHEDULER_SCHEMES = ("tcp", "tls", "ucx", "inproc")
#: Bound on ``local:N``: more worker processes than this on one machine is a typo, not a plan.
MAX_LOCAL_WORKERS = 256
#: ``local:N`` takes at most this many worker processes per core of this machine (cells wait on
#: model servers, so a few per core make sense; hundreds of processes on a laptop do not).
LOCAL_WORKERS_PER_CORE = 4

_LOCAL = re.compile(r"^local:(?P<count>[0-9]{1,6})$")

_ADDRESS = re.compile(r"^(?P<scheme>[a-z]+)://(?P<host>\[[0-9a-fA-F:.]+\]|[A-Za-z0-9.\-_]+)(:(?P<port>\d{1,5}))?/?$")


@dataclass(frozen=True)
class ClusterSpec:
    """A parsed ``--cluster`` value: either ``local_workers`` or ``address`` is set."""

    local_workers: int | None = None
    address: str | None = None

    def __str__(self) -> str:
        return f"local:{self.local_workers}" if self.local_workers is not None else str(self.address)


def parse_cluster_spec(value: str) -> ClusterSpec:
    """``"local:2"`` -> 2 local workers; ``"tcp://127.0.0.1:8786"`` -> that scheduler.

    Anything else raises :class:`~povagent.errors.ClusterError` naming the value and the two
    accepted forms.
    """
    text = value.strip()
    shown = text if len(text) <= 80 else text[:77] + "..."
    if text.startswith("local:"):
        most = local_worker_limit()
        # ASCII digits only, and few of them: int() of a superscript or of 5,000 digits raises
        local = _LOCAL.match(text)
        if local is None or not 1 <= int(local["count"]) <= most:
            raise ClusterError(
                f"--cluster {shown!r}: local:N takes a number of worker processes from 1 to {most} on this machine "
                f"({LOCAL_WORKERS_PER_CORE} per core); for more, start a scheduler and workers (docs/how-to/cluster.md)"
            )
        return ClusterSpec(local_workers=int(local["count"]))
    match = _ADDRESS.match(text)
    if match is None or match["scheme"] not in SCHEDULER_SCHEMES:
        raise ClusterError(
            f"--cluster {shown!r}: give local:N (N worker processes on this machine) or a scheduler's "
            "address such as tcp://HOST:8786"
        )
    if match["port"] is not None and not 0 < int(match["port"]) < 65536:
        raise ClusterError(f"--cluster {shown!r}: the port must be between 1 and 65535")
    return ClusterSpec(address=text.rstrip("/"))


def local_worker_limit() -> int:
    """The largest N ``local:N`` accepts here: ``LOCAL_WORKERS_PER_CORE`` per usable core."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return min(MAX_LOCAL_WORKERS, LOCAL_WORKERS_PER_CORE * max(1, cores))


def yaml_cluster_spec(value: str) -> ClusterSpec:
    """A YAML's ``cluster:`` value: ``local:N`` only; a scheduler's address is refused.

    A scheduler runs code on this machine (pickles travel both ways), and a YAML file is
    untrusted input: the address must come from ``--cluster`` or the library call.
    """
    spec = parse_cluster_spec(value)
    if spec.local_workers is None:
        raise ClusterError(
            f"{spec.address!r}: a YAML file may ask for local:N only; give a scheduler's address on the command line "
            "with --cluster (a Dask scheduler runs code on this machine: use only one you run, see docs/explanation/security.md)"
        )
    return spec
