"""The built-in plugins, loaded exactly like third-party ones (by module name).

Each entry is a module of ``povagent_plugins`` (the repository's ``plugins/`` folder) that
implements ``register_*`` hooks. Keep one module per line, grouped by kind.
"""

DEFAULT_PLUGINS: tuple[str, ...] = (
    # scorers
    "povagent_plugins.scorers.official",
    # parsers
    # strategies
    # backends
    # model profiles
)
