"""Pipeline and sweep configuration: data at the bottom of povagent, read and checked here,
acted on elsewhere (the runner, the engine, the image transports import it, never the reverse).

One module per job:

- ``pipeline``: the top-level functions (``load_pipeline``, ``pipeline_from_source``,
  ``dump_pipeline``, ``load_sweep``) that put the others together;
- ``models``: the schema, the pydantic models of every key with their defaults and bounds;
- ``retry_policy``: the retry policy's numbers (the engine's retry rule applies them);
- ``yaml_reader``: YAML with the line of every key, bounded (size, nesting, aliases, duplicate keys);
- ``validation_messages``: pydantic errors as ``file, line N: key: what is wrong``;
- ``plugin_checks``: the plugins a pipeline names, loaded, checked and resolved;
- ``plugin_rule``: which plugin modules a config may load at all;
- ``overrides``: merging an override into a pipeline document;
- ``quoting``: how values and key paths are quoted back in messages;
- ``profiles``: the model profiles a pipeline may name instead of a backend.
"""
