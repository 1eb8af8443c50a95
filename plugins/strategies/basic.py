"""The ``basic`` strategy: the paper's basic prompt, single-turn, 256 new tokens.

The example to copy for a new strategy: choose the prompt text (:meth:`BasicStrategy.prompt_text`),
choose the images (:meth:`BasicStrategy.images_for`), and let :mod:`.layout` assemble the
message and the answer schema. It must not call the model itself (the runner does, through
:meth:`povagent.interfaces.Strategy.solve`).
"""

from __future__ import annotations

from functools import lru_cache

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.dataset.instances import Instance
from povagent.exchange.messages import GenerationParams, Request
from povagent.exchange.images import ImageStore
from povagent.interfaces import Strategy
from povagent.exchange.prompts import frame_values, load_template, render
from povagent_plugins.strategies.layout import answer_spec, prompt_message, shown_images


#: Stands for the sentence while a template is filled once per frame size and count.
_SENTENCE = "\x00povagent-sentence\x00"


@lru_cache(maxsize=256, typed=True)
def _template_pieces(name: str, width: int, height: int, n_images: int | None) -> tuple[str, ...] | None:
    """Template ``name`` filled with the frame values, split where the sentence goes
    (``None`` if the template could hold the stand-in itself)."""
    if _SENTENCE in load_template(name):
        return None
    return tuple(render(name, sentence=_SENTENCE, **frame_values(width, height, n_images)).split(_SENTENCE))


def fill_sentence(name: str, sentence: str, width: int, height: int, n_images: int | None = None) -> str:
    """``render(name, sentence=sentence, **frame_values(width, height, n_images))``, with the
    template filled once per (template, frame size, frame count): only the sentence is joined in
    per instance. The same text: a placeholder is replaced in one pass, so the sentence is
    inserted as is wherever ``$sentence`` stands."""
    pieces = _template_pieces(name, width, height, n_images)
    if pieces is None:
        return render(name, sentence=sentence, **frame_values(width, height, n_images))
    return str(sentence).join(pieces)


class BasicStrategy(Strategy):
    """Basic prompt (Inferred/Stated with labelled frames; Given with the observer view).

    Options: ``max_tokens`` (default 256, as released), ``temperature`` (default: the backend's).
    """

    default_max_tokens = 256

    def __init__(self, max_tokens: int | None = None, temperature: float | None = None) -> None:
        max_tokens = self.default_max_tokens if max_tokens is None else max_tokens
        if not isinstance(max_tokens, int) or isinstance(max_tokens, bool) or max_tokens < 1:
            raise ValueError(f"strategy option max_tokens must be a positive integer, got {max_tokens!r}")
        if temperature is not None and (not isinstance(temperature, (int, float)) or temperature < 0):
            raise ValueError(f"strategy option temperature must be a number >= 0, got {temperature!r}")
        self.generation = GenerationParams(
            max_tokens=max_tokens, temperature=None if temperature is None else float(temperature)
        )

    def prompt_text(self, instance: Instance) -> str:
        """The filled prompt text for ``instance``."""
        width, height = instance.frame_size
        if instance.condition.uses_exploration_frames:
            return fill_sentence("basic_frames", instance.sentence, width, height, len(instance.frames))
        return fill_sentence("basic_given", instance.sentence, width, height)

    def images_for(self, instance: Instance, images: ImageStore) -> list[str]:
        """Hashes of the images shown, in order (the frames as they are)."""
        return shown_images(instance, images)

    def answer_spec(self, instance: Instance) -> AnswerSpec:
        """What this strategy asks for, without building the request (``povagent rescore`` uses
        it to re-parse a finished run without touching an image)."""
        return answer_spec(instance)

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """One user message (images first, then the prompt) asking for the paper's JSON answer."""
        message = prompt_message(instance, self.images_for(instance, images), self.prompt_text(instance))
        return Request(
            messages=(message,), answer=self.answer_spec(instance), generation=self.generation, instance=instance
        )


@hookimpl
def register_strategies(register) -> None:
    """Contribute the basic strategy."""
    register("basic", BasicStrategy, description="The paper's basic prompt (A/B with labelled frames, C with the observer view)")
