"""The one way povagent imports litellm: lazily, offline-safe, quiet.

``import litellm`` costs seconds and, unless told otherwise, fetches a model cost map from the
network and loads stray ``.env`` files. Everything that needs litellm calls
:func:`import_litellm` at the moment it needs it, so ``povagent --help``, offline baselines and
replays never import it. This module must stay tiny and must not import litellm at import time.
"""

from __future__ import annotations

import functools
import os
from types import ModuleType


@functools.cache
def import_litellm() -> ModuleType:
    """Import and return litellm, set up for closed networks and clean logs.

    Before the first import: ``LITELLM_LOCAL_MODEL_COST_MAP=True`` (use the cost map bundled
    with the package instead of downloading one) and ``LITELLM_MODE=PRODUCTION`` (do not load
    ``.env`` files). Both are defaults: a value the user exported wins.

    ``MAX_BASE64_LENGTH_FOR_LOGGING`` (also read at import) is left alone: litellm's truncation
    of base64 for logging is skipped per call instead, for povagent's calls only and only while
    nothing can read litellm's logging payload (:mod:`povagent.engine.llm_logging`).
    """
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    os.environ.setdefault("LITELLM_MODE", "PRODUCTION")
    import litellm

    # the "Give Feedback / Get Help" banner on every exception drowns our own error messages
    litellm.suppress_debug_info = True
    # anonymous usage telemetry would be a network call we never asked for
    litellm.telemetry = False
    return litellm


@functools.cache
def warm_up_litellm(model: str) -> None:
    """Load what litellm loads lazily on its first request (about 460 modules of the OpenAI
    client and litellm's own: seconds on a busy machine), so that cost never counts against
    the first request's timeout. Makes no network call: the OpenAI client is only built and
    the completion is litellm's ``mock_response``. Runs once per model string and process.
    """
    litellm = import_litellm()
    import openai

    client = openai.AsyncOpenAI(api_key="warm-up", base_url="http://127.0.0.1:9/v1")
    _ = client.chat.completions  # the resources module tree loads on first access
    try:
        litellm.completion(model=model, messages=[{"role": "user", "content": "warm-up"}], mock_response="ok")
    except Exception:  # a warm-up only saves time: a model string litellm cannot route fails later, for real
        pass
