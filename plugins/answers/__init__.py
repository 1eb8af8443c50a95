"""Built-in answer types (registered through ``register_answer_types`` like any plugin's)."""
