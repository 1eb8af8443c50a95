"""Pipeline and sweep configuration: YAML models and safe loading (``pipeline``) and the model
profiles a pipeline may name instead of a backend (``profiles``).
"""
