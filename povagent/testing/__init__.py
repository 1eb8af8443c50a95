"""Test tools for povagent and its plugin authors; nothing here loads unless asked for.

* :mod:`povagent.testing.pytest_plugin`: fixtures (a fresh plugin host, a queued backend, a
  running loopback server, a tiny release on disk). Opt in from a ``conftest.py`` with
  ``pytest_plugins = ["povagent.testing.pytest_plugin"]`` or on the command line with
  ``-p povagent.testing.pytest_plugin``.
* :mod:`povagent.testing.loopback_server`: an OpenAI-compatible chat server on 127.0.0.1
  (``python -m povagent.testing.loopback_server --help``); with ``--script FILE`` it replays a
  model's turns, texts and tool calls, from a file (:mod:`povagent.testing.scripted_turns`).
* :mod:`povagent.testing.hub_server`: a Hugging Face Hub file server on 127.0.0.1 serving a
  folder as a dataset repository, for ``snapshot_download`` and ``povagent download``
  (``python -m povagent.testing.hub_server FOLDER``).
"""
