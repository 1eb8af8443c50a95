"""Built-in surface judges for the dataset generator (plugins)."""
