"""The one request path shared by the runner and the agent: the retry policy and the
transient/permanent classification, the timeout rule, the response cache, and the lazy litellm
import.

It knows nothing of datasets, rows or run folders (those live in :mod:`povagent.run`).
"""
