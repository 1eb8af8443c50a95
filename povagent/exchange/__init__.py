"""What a model is shown: requests and responses (``messages``), the run-wide image store
(``images``), how images travel to the model (``transport``: inline, ``file://`` or the read-only
static server of ``image_server``), prompt templates (``prompts``) and a request rendered for a
person (``preview``).

Nothing here calls a model: sending a request is :mod:`povagent.engine`'s job.
"""
