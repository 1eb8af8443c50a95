"""A Dask client from a ``--cluster`` value, a user's own client, or nothing.

``cluster_client`` is the only place that imports ``distributed``. A missing extra is one line
naming ``pip install 'povagent[cluster]'``; an address that is not a Dask scheduler (nothing
listening, a port that accepts and never answers, a web server, a server answering other bytes,
a comm Dask cannot open here) is one line naming it, within :func:`connect_timeout` seconds: the
address is asked who it is (Dask's ``identity`` message) under a deadline before a client is
made. A client the caller built is used as is and never closed here; one this module started
(and its ``LocalCluster``, bound to 127.0.0.1 only) is closed on the way out.

What it must not do: take an address from a file. A scheduler runs code on this machine
(pickles travel both ways), so addresses come from ``--cluster`` or the library call only
(:func:`povagent.config.cluster_spec.yaml_cluster_spec`).
"""

from __future__ import annotations

import asyncio
import importlib.util
import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from povagent.config.cluster_spec import ClusterSpec, parse_cluster_spec
from povagent.errors import ClusterError

if TYPE_CHECKING:
    from distributed import Client

#: How long to wait for a scheduler that does not answer before saying so.
CONNECT_TIMEOUT_S = 20.0
#: Environment variable that shortens (or lengthens) that wait, in seconds (the tests use it).
CONNECT_TIMEOUT_ENV = "POVAGENT_CLUSTER_CONNECT_TIMEOUT_S"
#: The only interface a ``local:N`` cluster listens on.
LOCAL_HOST = "127.0.0.1"

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
    if spec.local_workers is not None:
        with _local_cluster(spec.local_workers) as client:
            yield client
        return
    assert spec.address is not None
    client = _connect(spec.address, connect_timeout())
    try:
        yield client
    finally:
        client.close()


def connect_timeout() -> float:
    """Seconds to wait for a scheduler's answer: ``CONNECT_TIMEOUT_S``, or the environment's
    ``POVAGENT_CLUSTER_CONNECT_TIMEOUT_S`` when it holds a positive number."""
    try:
        value = float(os.environ.get(CONNECT_TIMEOUT_ENV, ""))
    except ValueError:
        return CONNECT_TIMEOUT_S
    return value if math.isfinite(value) and value > 0 else CONNECT_TIMEOUT_S


@contextmanager
def _local_cluster(workers: int) -> Iterator[Client]:
    """A ``LocalCluster`` of ``workers`` single-threaded processes, listening on 127.0.0.1 only.

    Its scheduler, workers and nannies bind to 127.0.0.1, and so does the scheduler's HTTP server
    (its pages show workers, logs, call stacks and task errors; the dashboard too when bokeh is
    installed), on a free port so nothing clashes on 8787. Workers serve no HTTP pages. Local
    workers print to the user's terminal: their structured house logs are kept to warnings and
    errors there (LOCAL_WORKER_LOG_LEVEL).
    """
    import dask
    import distributed

    with dask.config.set({WORKER_LOG_LEVEL: LOCAL_WORKER_LOG_LEVEL}):
        try:
            local = distributed.LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                host=LOCAL_HOST,
                dashboard_address=f"{LOCAL_HOST}:0",
                worker_dashboard_address=None,
                silence_logs=50,
            )
        except Exception as exc:  # no port, no process, no memory: nothing of ours is running
            raise ClusterError(f"could not start local:{workers} (a Dask LocalCluster on this machine): {_one_line(exc)}") from None
        with local, distributed.Client(local) as client:
            yield client


def _connect(address: str, timeout: float) -> Client:
    """A client of the scheduler at ``address``, or one :class:`ClusterError` within ``timeout`` s.

    ``distributed.Client`` waits for good on a port that accepts and never answers (and on a web
    server), and raises whatever its comm met on other bytes. So the address is first asked
    who it is, over Dask's own comm, with every step under one deadline; only a Dask scheduler
    gets a client.
    """
    import distributed

    try:
        kind = _ask(address, timeout)
    except TimeoutError:
        raise ClusterError(f"no Dask scheduler answered at {address} within {timeout:g} s: is it the scheduler's address and port?") from None
    except Exception as exc:  # the comm layer's errors vary by scheme, version and peer
        raise ClusterError(f"no Dask scheduler at {address}: {_one_line(exc)}{_scheme_hint(address)}") from None
    if kind != "Scheduler":
        raise ClusterError(f"{address} answered, but not as a Dask scheduler (it says it is {str(kind)[:40]!r}): give the scheduler's address")
    try:
        return distributed.Client(address, timeout=timeout)
    except Exception as exc:
        raise ClusterError(f"could not connect to the Dask scheduler at {address}: {_one_line(exc)}") from None


def _ask(address: str, timeout: float) -> object:
    """:func:`_identity` under one deadline, on a loop of its own (in a thread when the caller
    already runs one: a notebook)."""
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return asyncio.run(asyncio.wait_for(_identity(address, timeout), timeout))
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(1) as pool:
        return pool.submit(lambda: asyncio.run(asyncio.wait_for(_identity(address, timeout), timeout))).result()


async def _identity(address: str, timeout: float) -> object:
    """What the server at ``address`` says it is (a Dask scheduler says ``"Scheduler"``)."""
    from distributed.comm import connect
    from distributed.security import Security

    comm = await connect(address, timeout=timeout, **Security().get_connection_args("client"))
    try:
        await comm.write({"op": "identity", "reply": True})
        answer = await comm.read()
    finally:
        comm.abort()
    return answer.get("type") if isinstance(answer, dict) else type(answer).__name__


def _scheme_hint(address: str) -> str:
    """What a scheme other than tcp:// needs here, for the one-line error."""
    if address.startswith("tls://"):
        return " (tls:// needs Dask's TLS settings: distributed.comm.tls.ca-file and .client.cert/.key in the Dask config)"
    if address.startswith("ucx://"):
        return " (ucx:// needs UCX and its Dask comm installed here)"
    if address.startswith("inproc://"):
        return " (inproc:// names a scheduler inside this very process, which only the library call can have)"
    return ""


def _one_line(exc: BaseException) -> str:
    """An exception as one short line: its type and its message's first line."""
    kind = type(exc).__name__
    if kind.islower():  # struct.error, socket.gaierror: the module says what it is
        kind = f"{type(exc).__module__}.{kind}"
    first = str(exc).strip().splitlines()[0][:200] if str(exc).strip() else ""
    return f"{kind}: {first}" if first else kind


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
