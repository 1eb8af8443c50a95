"""Built-in strategies (plugins)."""
