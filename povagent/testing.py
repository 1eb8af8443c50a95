"""pytest plugin for povagent and its plugin authors (loaded through the ``pytest11`` entry point).

Fixtures are added here as the framework grows; see the README's "Writing plugins" section.
"""
