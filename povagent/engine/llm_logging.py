"""litellm's base64 truncation for logging, skipped for povagent's calls while nobody can read it.

After every successful call litellm copies the messages and replaces each long base64 data URL
by a size placeholder (``truncate_base64_in_messages_async``, a regex pass over the whole
payload: ~7.5 MB for a 30-frame POVBench request), so that the standard logging payload it
hands its logging callbacks never carries whole images. It does so on every call, whether or
not anything will ever read that payload; measured, it is about a third of the client's CPU
per inline request (``benchmarks/bench_base64_logging.py``).

:func:`skip_truncation_when_unobserved` (called by the litellm backend's ``start``) puts a
wrapper in front of that function. The wrapper returns the messages untouched only when both
hold at the moment litellm would shorten them:

* the call is povagent's own (:func:`povagent_call` marks it; the mark travels with the call's
  context into litellm's logging worker, which runs each handler in the caller's context), and
  the call named no callback of its own;
* :func:`logging_payload_unobserved`: no litellm callback of any kind is registered, litellm's
  debug/verbose logging is off, and ``LITELLM_PRINT_STANDARD_LOGGING_PAYLOAD`` (which prints the
  payload) is unset.

Otherwise litellm's own function runs, exactly as without povagent. Deciding at the moment of
truncation, not once at start, means a callback registered mid-run (an application embedding the
grounding agent may add one at any time) receives shortened images from then on; scoping to
povagent's calls means litellm calls the application makes itself are never changed. A user who
exported ``MAX_BASE64_LENGTH_FOR_LOGGING`` chose litellm's behaviour themselves: then nothing is
installed.

litellm is pinned exactly (pyproject.toml); tests/engine/test_llm_logging.py pins what this
module relies on (the function's name and place, the callback lists, where the payload goes).
Should a future litellm move any of it, :func:`skip_truncation_when_unobserved` installs nothing
and litellm truncates as usual: the safe side. Never imports litellm at import time.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
from collections.abc import Iterator, Mapping
from types import ModuleType
from typing import Any

#: The environment setting litellm reads at import; set by the user, it is theirs to decide.
USER_SETTING = "MAX_BASE64_LENGTH_FOR_LOGGING"
#: litellm prints every standard logging payload to stdout when this is set.
PRINT_PAYLOAD_SETTING = "LITELLM_PRINT_STANDARD_LOGGING_PAYLOAD"
#: Every litellm module list through which a callback can receive a call's logging data.
CALLBACK_LISTS = (
    "callbacks",
    "success_callback",
    "failure_callback",
    "input_callback",
    "service_callback",
    "audit_log_callbacks",
    "_async_success_callback",
    "_async_failure_callback",
    "_async_input_callback",
)
#: litellm module lists whose names say "callback" but which register nothing (a catalogue of
#: the integrations litellm knows by name).
NOT_CALLBACK_LISTS = frozenset({"_known_custom_logger_compatible_callbacks"})
#: litellm's loggers; any of them at DEBUG means litellm's debug output is on.
LITELLM_LOGGERS = ("LiteLLM", "LiteLLM Router", "LiteLLM Proxy")

#: Set while povagent's own litellm call is being made (and so in its logging handler's context).
_POVAGENT_CALL: contextvars.ContextVar[bool] = contextvars.ContextVar("povagent_litellm_call", default=False)


def logging_payload_unobserved(litellm: ModuleType) -> bool:
    """Whether nothing can receive litellm's logging payload right now: no callback in any of
    litellm's callback lists, litellm's debug/verbose logging off, and the payload not printed.
    Cheap (a few list and flag reads): it is asked once per call."""
    for name in CALLBACK_LISTS:
        if getattr(litellm, name, None):
            return False
    if getattr(litellm, "set_verbose", False) or os.environ.get(PRINT_PAYLOAD_SETTING):
        return False
    return not any(logging.getLogger(name).isEnabledFor(logging.DEBUG) for name in LITELLM_LOGGERS)


def names_callbacks(call_kwargs: Mapping[str, Any]) -> bool:
    """Whether a call's own keyword arguments name a callback (litellm's per-call
    ``callbacks=``, ``success_callback=``, ``logger_fn=``...): such a call is observed."""
    return any("callback" in key or key == "logger_fn" for key in call_kwargs)


@contextlib.contextmanager
def povagent_call(call_kwargs: Mapping[str, Any]) -> Iterator[None]:
    """Mark the litellm call made inside this block as povagent's own (unless ``call_kwargs``
    name a callback of their own). The mark is reset on leaving, so later code in the same
    task (an application's own litellm calls) is not marked."""
    token = _POVAGENT_CALL.set(not names_callbacks(call_kwargs))
    try:
        yield
    finally:
        _POVAGENT_CALL.reset(token)


def skip_truncation_when_unobserved(litellm: ModuleType) -> bool:
    """Install the wrapper described in the module docstring (once per process); returns
    whether it is installed. Nothing is installed when the user exported
    ``MAX_BASE64_LENGTH_FOR_LOGGING`` or when litellm no longer has the function where the
    pinned version keeps it."""
    if os.environ.get(USER_SETTING) is not None:
        return False
    try:
        from litellm.litellm_core_utils import litellm_logging
    except ImportError:
        return False
    original = getattr(litellm_logging, "truncate_base64_in_messages_async", None)
    if original is None:
        return False
    if getattr(original, "__povagent_wrapped__", None) is not None:
        return True

    async def truncate_unless_unobserved(messages: Any) -> Any:
        # the user's own setting is read again here: exported after start, it still wins
        if _POVAGENT_CALL.get() and os.environ.get(USER_SETTING) is None and logging_payload_unobserved(litellm):
            return messages
        return await original(messages)

    truncate_unless_unobserved.__povagent_wrapped__ = original  # type: ignore[attr-defined]
    truncate_unless_unobserved.__doc__ = original.__doc__
    litellm_logging.truncate_base64_in_messages_async = truncate_unless_unobserved
    return True
