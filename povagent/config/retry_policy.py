"""The retry policy as configuration: how many attempts a request gets and how long to wait.

A pipeline's ``retry:`` and the agent's ``retry=`` are both a :class:`RetryPolicy`, bounded so
that no configuration can make a run wait forever. It is data, read by the pipeline's models
(:mod:`povagent.config.models`) and applied by the engine: which failures are retried and how
long each wait is are the engine's rule (:mod:`povagent.engine.retry`). This module must not
classify failures, sleep, or import the engine.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

#: Longest wait a policy may configure between two attempts (seconds): one hour.
MAX_POLICY_WAIT_S = 3600.0

#: Most attempts a policy may configure for one request.
MAX_ATTEMPTS = 100


class RetryPolicy(BaseModel):
    """Retries on transient failures: ``attempts`` in all (first try included), exponential
    backoff from ``initial_wait`` to ``max_wait`` seconds; a server's Retry-After wins.

    The one retry policy type: a pipeline's ``retry:`` and the agent's ``retry=`` are both
    this. Every number is finite and bounded, so no configuration can make a run wait forever.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    attempts: int = Field(5, ge=1, le=MAX_ATTEMPTS)
    initial_wait: float = Field(1.0, ge=0, le=MAX_POLICY_WAIT_S)
    max_wait: float = Field(60.0, ge=0, le=MAX_POLICY_WAIT_S)
