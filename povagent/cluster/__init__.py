"""The one room that knows the distributed engine (Dask distributed).

What it is for: turning a ``--cluster`` value (or a user's own ``distributed.Client``) into a
client, and running plain, idempotent functions of one unit (a house, a sweep cell, a shard) on
it. What it must not do: be imported on the default path. ``generate/`` and ``run/`` hand it
plain functions and never import dask themselves; without ``--cluster`` nothing here is loaded.
"""

from __future__ import annotations

from povagent.config.cluster_spec import ClusterSpec, parse_cluster_spec

__all__ = ["ClusterSpec", "parse_cluster_spec"]
