"""What ``--cluster`` (or a YAML's ``cluster:`` key) names, read without importing Dask.

A configuration value like any other, so it sits with the configuration: checking a config never
imports :mod:`povagent.cluster`, which only ``--cluster`` loads. Two forms: ``local:N`` starts a
Dask ``LocalCluster`` of N worker processes on this machine; ``tcp://HOST:PORT`` (or ``tls://``)
connects to a scheduler that is already running. Parsing is pure so a config can be checked, and
a bad value refused, before anything starts.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from povagent.errors import ClusterError

#: Schemes of a running scheduler's address that Dask's comm layer speaks.
SCHEDULER_SCHEMES = ("tcp", "tls", "ucx", "inproc")
#: Bound on ``local:N``: more worker processes than this on one machine is a typo, not a plan.
MAX_LOCAL_WORKERS = 256

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
        count = text.removeprefix("local:")
        if not count.isdigit() or not 1 <= int(count) <= MAX_LOCAL_WORKERS:
            raise ClusterError(f"--cluster {shown!r}: local:N takes a number of worker processes from 1 to {MAX_LOCAL_WORKERS}")
        return ClusterSpec(local_workers=int(count))
    match = _ADDRESS.match(text)
    if match is None or match["scheme"] not in SCHEDULER_SCHEMES:
        raise ClusterError(
            f"--cluster {shown!r}: give local:N (N worker processes on this machine) or a scheduler's "
            "address such as tcp://HOST:8786"
        )
    if match["port"] is not None and not 0 < int(match["port"]) < 65536:
        raise ClusterError(f"--cluster {shown!r}: the port must be between 1 and 65535")
    return ClusterSpec(address=text.rstrip("/"))
