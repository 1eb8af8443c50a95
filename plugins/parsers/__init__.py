"""Built-in parsers (plugins)."""
