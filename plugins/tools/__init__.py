"""The built-in active-mode tools, one module each, registered like any plugin's (``register_tools``).

Their names, schemas and meanings are fixed: results compare across models and papers by them.
"""
