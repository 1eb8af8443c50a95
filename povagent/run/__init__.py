"""Running pipelines and sweeps: the runner, the row journal, instance selection and pending keys,
summaries, progress and logs, offline re-scoring and the quickstart.

Effects live here (files, clocks, concurrency); rules it applies come from the pure packages.
"""
