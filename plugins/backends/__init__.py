"""Built-in backends (plugins)."""
