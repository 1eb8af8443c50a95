"""A Dask client from a ``--cluster`` value, a user's own client, or nothing.

``cluster_client`` is the only place that imports ``distributed``. A missing extra is one line
naming ``pip install 'povagent[cluster]'``; a scheduler that cannot be reached is one line naming
its address. A client the caller built is used as is and never closed here; one this module
started (and its ``LocalCluster``) is closed on the way out.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from povagent.config.cluster_spec import ClusterSpec, parse_cluster_spec
from povagent.errors import ClusterError

if TYPE_CHECKING:
    from distributed import Client

#: How long to wait for a scheduler that does not answer before saying so.
CONNECT_TIMEOUT_S = 20

#: Dask config key read by povagent's worker tasks: the level of their structured log lines.
WORKER_LOG_LEVEL = "povagent.worker-log-level"
LOCAL_WORKER_LOG_LEVEL = "warning"

MISSING_EXTRA = "Dask is not installed: --cluster needs the cluster extra, pip install 'povagent[cluster]'"


def require_distributed() -> None:
    """Raise :class:`ClusterError` naming the extra when ``distributed`` cannot be imported."""
    if importlib.util.find_spec("distributed") is None:
        raise ClusterError(MISSING_EXTRA)


@contextmanager
def cluster_client(cluster: str | ClusterSpec | Any | None) -> Iterator[Client | None]:
    """Yield a ``distributed.Client`` for ``cluster``, or ``None`` when it is ``None``.

    ``cluster`` is a ``--cluster`` string, a parsed :class:`ClusterSpec`, or a
    ``distributed.Client`` (used as is, left open). ``local:N`` starts a ``LocalCluster`` of N
    single-threaded worker processes (the units are CPU-bound numpy work: processes, not threads).
    """
    if cluster is None:
        yield None
        return
    if not isinstance(cluster, (str, ClusterSpec)):
        if type(cluster).__name__ != "Client":
            raise ClusterError(f"cluster must be local:N, a scheduler address or a distributed.Client, not {type(cluster).__name__}")
        yield cluster
        return
    spec = parse_cluster_spec(cluster) if isinstance(cluster, str) else cluster
    require_distributed()
    import distributed

    if spec.local_workers is not None:
        import dask

        # ":0": the scheduler's HTTP server (which serves the dashboard when bokeh is there) on a
        # free port, never a clash on 8787. Local workers print to the user's terminal: their
        # structured house logs are kept to warnings and errors there (LOCAL_WORKER_LOG_LEVEL).
        with dask.config.set({WORKER_LOG_LEVEL: LOCAL_WORKER_LOG_LEVEL}), distributed.LocalCluster(
            n_workers=spec.local_workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            silence_logs=50,
        ) as local, distributed.Client(local) as client:
            yield client
        return
    try:
        client = distributed.Client(spec.address, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as exc:
        raise ClusterError(f"no Dask scheduler answered at {spec.address} within {CONNECT_TIMEOUT_S} s ({type(exc).__name__})") from None
    try:
        yield client
    finally:
        client.close()


def dashboard_link(client: Client) -> str | None:
    """The Dask dashboard's address, when the scheduler really serves one (it needs bokeh there)."""
    try:
        served = "dashboard" in client.scheduler_info().get("services", {})
        served = served and bool(client.run_on_scheduler(_has_bokeh))
        link = client.dashboard_link if served else None
    except Exception:  # the scheduler went away or answers oddly: there is nothing to show
        return None
    return str(link) if link else None


def _has_bokeh() -> bool:
    """On the scheduler: whether bokeh (the dashboard's one requirement) is importable there."""
    return importlib.util.find_spec("bokeh") is not None
