"""Running pipelines and sweeps: the runner, the row journal, instance selection and pending keys,
summaries, progress and offline re-scoring.

Effects live here (files, clocks, concurrency); rules it applies come from the pure packages.
"""
