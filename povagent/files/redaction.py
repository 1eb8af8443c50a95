"""Redaction: secrets never reach a file or a terminal.

:class:`Redactor` removes values of keys named like a secret, ``sk-...`` keys, ``Bearer ...``
tokens, credentials inside URLs (``http://user:password@host``), a key pasted into a ``*_env``
field where a variable's name belongs, and the current values of ``*_API_KEY`` (and
``*_TOKEN``/``*_SECRET``) environment variables. Run logs pass every event through it; error
messages stored in result rows, the resolved ``config.yaml``, the report's pages and the
configuration checks use the same one.

It sits on the ground floor with the confined reads and writes: every room that writes what a
user or a server handed it stands on it. This module only recognises and removes secrets; it
must not write, log or decide what is logged.
"""

from __future__ import annotations

import functools
import os
import re
from typing import Any, Mapping

from structlog.typing import EventDict

REDACTED = "[REDACTED]"

#: Keys whose string values are secrets. Counts stay (``prompt_tokens`` is a number).
_SECRET_KEY = re.compile(r"(key|token|secret|authorization|password|passwd|cookie|credential)", re.IGNORECASE)
#: Keys that match the pattern above but never hold a secret.
_NOT_SECRET = frozenset({"row", "key_count", "cache_key", "request_hash", "config_hash"})
_SECRET_TEXT = [
    re.compile(r"sk-[A-Za-z0-9_\-]{8,}"),
    re.compile(r"(?i:bearer)\s+[A-Za-z0-9._~+/=\-]{8,}"),
    re.compile(r"AIza[0-9A-Za-z_\-]{20,}"),  # Google API keys
    # The user-info part of a URL (``scheme://user:password@host``): scheme and host stay.
    re.compile(r"(?<=://)[^\s/?#@]+(?=@)"),
]
#: What a plausible environment variable name looks like (``OPENAI_API_KEY``, ``my_key_2``).
ENV_VAR_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
#: What a ``*_env`` field wants, for messages refusing a value (which they never repeat).
ENV_NAME_WANTED = (
    "wants the name of an environment variable that holds the key (letters, digits and _, not "
    "starting with a digit, e.g. OPENAI_API_KEY), not the key itself; the value given is not such "
    "a name and is not shown (it may be a key). Export the key (export MY_KEY=...) and write "
    "api_key_env: MY_KEY"
)
#: Longer "names" are refused too: a variable name is a word, a key is a long random string.
MAX_VARIABLE_NAME = 64
_SECRET_ENV = re.compile(r".*(_API_KEY|_TOKEN|_SECRET|_ACCESS_KEY)$|^API_KEY$", re.IGNORECASE)

class Redactor:
    """Removes secrets from strings and nested structures.

    Environment secrets are read when the redactor is made (a run makes one at start), so a
    key exported later is not known; pass ``extra_secrets`` for values from elsewhere.
    """

    def __init__(self, extra_secrets: tuple[str, ...] = ()) -> None:
        secrets = {v for k, v in os.environ.items() if _SECRET_ENV.match(k) and len(v) >= 6}
        secrets.update(s for s in extra_secrets if s and len(s) >= 6)
        patterns = list(_SECRET_TEXT)
        #: the secret values themselves (no pattern): what :meth:`known` removes from answers
        self._known: re.Pattern[str] | None = None
        if secrets:
            # Longest first so a key containing another is removed whole.
            self._known = re.compile("|".join(re.escape(s) for s in sorted(secrets, key=len, reverse=True)))
            patterns.append(self._known)
        self._patterns = patterns
        # One search decides the common case (nothing to redact); it runs on every logged string.
        self._any = re.compile("|".join(f"(?:{p.pattern})" for p in patterns))

    def text(self, value: str) -> str:
        """``value`` with every secret-looking substring replaced."""
        if not self._any.search(value):
            return value
        for p in self._patterns:
            value = p.sub(REDACTED, value)
        return value

    @property
    def knows_secrets(self) -> bool:
        """Whether any secret value is known (else :meth:`known` changes nothing)."""
        return self._known is not None

    def known(self, value: str) -> str:
        """``value`` with every secret value povagent knows replaced, and nothing else touched.

        For what a server sends back in a successful answer (a server echoing the request's
        ``Authorization`` header): an answer is kept exactly as sent, except for the keys
        povagent itself holds; the secret-looking patterns of :meth:`text` are for messages.
        """
        if self._known is None or not self._known.search(value):
            return value
        return self._known.sub(REDACTED, value)

    def value(self, value: Any, key: str | None = None) -> Any:
        """Redact a value found under ``key`` (recursing into mappings and lists)."""
        if value is None or isinstance(value, (int, float)):
            return value  # counts, sizes and flags are never secrets (``prompt_tokens`` stays)
        if key is not None and _secret_key(key):
            return REDACTED
        if key is not None and isinstance(value, str) and _names_a_variable(key) and not self.plausible_variable_name(value):
            return REDACTED  # not a variable's name: most likely the key itself, pasted
        if isinstance(value, str):
            return self.text(value)
        if isinstance(value, Mapping):
            return {k: self.value(v, str(k)) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [self.value(v) for v in value]
        return value

    def plausible_variable_name(self, value: str) -> bool:
        """Whether ``value`` can be the *name* of an environment variable (``OPENAI_API_KEY``)
        rather than a secret: name characters only, and nothing a secret pattern or a current
        secret's value matches (``AIza...`` keys are made of name characters too)."""
        return bool(ENV_VAR_NAME.match(value)) and len(value) <= MAX_VARIABLE_NAME and self.text(value) == value

    def __call__(self, logger: Any, method: str, event: EventDict) -> dict[str, Any]:
        """structlog processor."""
        return self.fields(event)

    def fields(self, event: Mapping[str, Any]) -> dict[str, Any]:
        """``{key: self.value(value, key)}`` for each field of ``event``, in its order (each
        field's redaction depends on its own key and value only)."""
        # What :meth:`value` gives, with its checks told apart once: a number, a flag or None
        # is kept, and a text under a key that names no secret is :meth:`text`'s (a run logs
        # an event a request, and these are nearly all of its fields)
        return {
            k: v if (kind := type(v)) in _NO_SECRET else self.text(v) if kind is str and _plain_key(k) else self.value(v, k)
            for k, v in event.items()
        }


#: The types :meth:`Redactor.value` returns unchanged whatever their key (counts, sizes, flags).
_NO_SECRET = frozenset({int, float, bool, type(None)})


@functools.lru_cache(maxsize=1024)
def _plain_key(key: str) -> bool:
    # a key under which :meth:`Redactor.value` treats a text as text: neither a secret's name
    # nor one naming an environment variable
    return not _secret_key(key) and not _names_a_variable(key)


_LITELLM_ENV_REF = "os.environ/"


def secrets_named_by(config: Any) -> tuple[str, ...]:
    """The values of the environment variables a resolved config names in its ``*_env`` fields
    (a backend's ``api_key_env``, each router deployment's) or by litellm's ``os.environ/NAME``
    reference: keys povagent sends, whatever the variable is called (``MY_LAB_KEY`` matches no
    secret-looking name). Unset ones are skipped."""
    found: list[str] = []

    def walk(node: Any) -> None:
        if isinstance(node, Mapping):
            for k, v in node.items():
                # ``api_key_env: NAME``, and litellm's own reference ``api_key: os.environ/NAME``
                name = v if isinstance(v, str) and _names_a_variable(str(k)) else None
                if isinstance(v, str) and v.startswith(_LITELLM_ENV_REF):
                    name = v[len(_LITELLM_ENV_REF):]
                if name is not None and ENV_VAR_NAME.match(name):
                    value = os.environ.get(name)
                    if value:
                        found.append(value)
                else:
                    walk(v)
        elif isinstance(node, (list, tuple)):
            for v in node:
                walk(v)

    walk(config)
    return tuple(found)


@functools.lru_cache(maxsize=1024)
def _secret_key(key: str) -> bool:
    # ``api_key_env: OPENAI_API_KEY`` names a variable; its value is not the secret.
    return key not in _NOT_SECRET and not key.lower().endswith("_env") and bool(_SECRET_KEY.search(key))


def _names_a_variable(key: str) -> bool:
    # ``api_key_env``, ``token_env``: fields whose value is the name of an environment variable
    return key.lower().endswith("_env")
