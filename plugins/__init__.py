"""Built-in povagent plugins, installed as ``povagent_plugins``.

Every module here is an ordinary pluggy plugin: its only link to the core is its
``register_*`` hook implementation, exactly as a third-party plugin would write it.
"""
