"""A checkpoint's chat template, rendered once when the model loads, before any request.

A chat template is Jinja code that comes with the checkpoint (``chat_template.jinja``,
``tokenizer_config.json``): untrusted input. ``transformers`` renders it in Jinja's
``ImmutableSandboxedEnvironment``, which refuses attributes starting with ``_`` (the usual way
out to Python's internals: ``''.__class__.__mro__``, ``cycler.__init__.__globals__``) and
methods that change lists and dicts, but lets a template call any other public method of any
object it is shown. The images of a conversation are such objects: a template given the
decoded pictures could call ``image.save(path)`` (a file written anywhere) or ``image.show()``
(a viewer program started). ``transformers`` releases that rebuild what a template sees from
plain JSON values (media become the placeholder ``"<Image>"``) close that; this module checks
at load that the installed one does, so that guarantee does not rest on a version pin.

Then the checkpoint's own template is rendered for a conversation shaped like a request (a
system text, a user turn of text and an image): a template that tries an escape (refused by the
sandbox with ``SecurityError``), raises, or does not render is refused in one line naming the
checkpoint, instead of failing every request in turn.

What the sandbox does not bound: a template may still spend time and memory (nested loops,
``"x" * 10**9``); the load then never ends, and a stop (Ctrl-C, SIGTERM) still ends the run,
since loading runs in a daemon thread (:mod:`povagent.engine.daemon_threads`).
"""

from __future__ import annotations

from typing import Any

from PIL import Image

#: A template that says whether the image it is shown is a plain placeholder string.
_SEES_PLAIN_DATA = "{{ messages[0]['content'][0]['image'] is string }}"


class ChatTemplateRefused(ValueError):
    """The checkpoint's chat template (or the installed ``transformers``) is unsafe or broken."""


def _probe_conversation() -> list[dict[str, Any]]:
    picture = Image.new("RGB", (8, 8))
    return [
        {"role": "system", "content": "You are a robot."},
        {"role": "user", "content": [{"type": "text", "text": "Image 0:"}, {"type": "image", "image": picture}, {"type": "text", "text": "Where?"}]},
    ]


def check_chat_template(processor: Any) -> None:
    """Refuse, with :class:`ChatTemplateRefused`, a ``transformers`` that shows templates live
    objects, or a chat template that does not render a request-shaped conversation (the
    message says what; the caller names the checkpoint)."""
    import transformers

    picture_only = [{"role": "user", "content": [{"type": "image", "image": Image.new("RGB", (8, 8))}]}]
    try:
        plain = processor.apply_chat_template(picture_only, chat_template=_SEES_PLAIN_DATA, tokenize=False)
    except Exception as exc:  # an old apply_chat_template without chat_template=: cannot be checked
        raise ChatTemplateRefused(
            f"cannot check how transformers {transformers.__version__} shows images to chat templates "
            f"({type(exc).__name__}: {str(exc)[:160]}); upgrade transformers"
        ) from None
    if str(plain).strip() != "True":
        raise ChatTemplateRefused(
            f"transformers {transformers.__version__} shows chat templates the decoded images themselves, whose "
            "methods write files (image.save); upgrade transformers to a release that renders templates from plain data"
        )
    try:
        processor.apply_chat_template([_probe_conversation()], tokenize=False, add_generation_prompt=True)
    except Exception as exc:  # jinja2's SecurityError, UndefinedError, TemplateError; a missing template
        reason = " ".join(f"{type(exc).__name__}: {exc}".split())[:240]
        raise ChatTemplateRefused(f"its chat template does not render a request ({reason})") from None
