"""The one request path shared by the runner and the agent: the retry rule (the
transient/permanent classification and the waits; the policy's numbers are configuration,
:mod:`povagent.config.retry_policy`), the timeout rule, the response cache, and the lazy litellm
import.

It knows nothing of datasets, rows or run folders (those live in :mod:`povagent.run`).
"""
