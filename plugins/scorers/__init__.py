"""Built-in scorers (plugins)."""
