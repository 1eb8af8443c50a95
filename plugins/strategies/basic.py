"""The ``basic`` strategy: the basic prompt as the authors' runner sent it, single-turn, 256 new tokens.

The example to copy for a new strategy: choose the prompt text (:meth:`BasicStrategy.prompt_text`),
choose the images (:meth:`BasicStrategy.images_for`), and let :mod:`.layout` assemble the
message and the answer schema. It must not call the model itself (the runner does, through
:meth:`povagent.interfaces.Strategy.solve`).

Options shared by every built-in strategy:

* ``prompts``: the prompt family (:mod:`.prompt_sets`): ``runner`` (default), ``appendix``,
  ``molmopoint``, ``robopoint``;
* ``max_tokens``: the new-token budget (``null``: no limit sent); the strategy's own default
  (256; CoT and S-CoT 1,024) unless a model profile or the pipeline sets one;
* ``temperature``: default the backend's (none sent);
* ``max_frames``: how many of the instance's frames A/B show, in the official order (the main
  runner shows every frame; its ablation scripts the first 30). ``null``: all.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import CONDITIONS, Condition
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, Request
from povagent.exchange.prompts import frame_values, load_template, render
from povagent.interfaces import Strategy
from povagent_plugins.strategies.layout import answer_spec, prompt_message, shown_images
from povagent_plugins.strategies.prompt_sets import DEFAULT_PROMPTS, PromptSet, prompt_set

#: The most frames the authors' ablation scripts (``run_vlm_eval_ab0.py`` .. ``ab4.py``) show:
#: the first 30 of the official order. Their main runner shows every frame.
ABLATION_MAX_FRAMES = 30

#: Stands for the sentence while a template is filled once per frame size and count.
_SENTENCE = "\x00povagent-sentence\x00"

#: An option left out (``None`` is a value: "no limit", "all frames").
_UNSET: Any = object()


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


def _positive_or_none(value: Any, option: str, what: str) -> int | None:
    if value is None:
        return None
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        raise ValueError(f"strategy option {option} must be a positive integer or null ({what}), got {value!r}")
    return value


def generation_options(max_tokens: int | None, temperature: Any) -> GenerationParams:
    """What a strategy's ``max_tokens`` (checked by the caller) and ``temperature`` options ask of
    the model; ``temperature`` is a number >= 0, or ``None`` for the model's own."""
    if temperature is not None and (not isinstance(temperature, (int, float)) or isinstance(temperature, bool) or temperature < 0):
        raise ValueError(f"strategy option temperature must be a number >= 0, got {temperature!r}")
    return GenerationParams(max_tokens=max_tokens, temperature=None if temperature is None else float(temperature))


class BasicStrategy(Strategy):
    """Basic prompt (Inferred/Stated with labelled frames; Given with the labelled observer view).

    Options: see the module docstring (``prompts``, ``max_tokens``, ``temperature``, ``max_frames``).
    """

    default_max_tokens: int | None = 256
    #: Frames shown by default (``None``: all, as the main runner).
    default_max_frames: int | None = None
    #: The conditions the authors ran this strategy on; others are outside the paper's protocol.
    paper_conditions: tuple[Condition, ...] = CONDITIONS

    def __init__(
        self,
        max_tokens: int | None = _UNSET,
        temperature: float | None = None,
        prompts: str = DEFAULT_PROMPTS,
        max_frames: int | None = _UNSET,
    ) -> None:
        max_tokens = self.default_max_tokens if max_tokens is _UNSET else max_tokens
        self.generation = generation_options(_positive_or_none(max_tokens, "max_tokens", "null sends no limit"), temperature)
        self.prompts: PromptSet = prompt_set(prompts)
        self._check_prompts()
        self.max_frames = _positive_or_none(
            self.default_max_frames if max_frames is _UNSET else max_frames, "max_frames", "null shows every frame"
        )

    def _check_prompts(self) -> None:
        """Refuse a prompt family this strategy has no text in (the basic strategy has all)."""

    # -- what is shown -----------------------------------------------------------------------
    def shown_frames(self, instance: Instance) -> tuple[Frame, ...]:
        """The frames shown, in the official order: A/B the first ``max_frames``; C the observer view."""
        if instance.povbench_condition.uses_exploration_frames and self.max_frames is not None:
            return instance.frames[: self.max_frames]
        return instance.frames

    def outside_paper_protocol(self, instance: Instance) -> bool:
        """Whether the authors never ran this strategy on ``instance``'s condition."""
        return instance.condition not in self.paper_conditions

    def prompt_text(self, instance: Instance) -> str:
        """The filled prompt text for ``instance``."""
        width, height = instance.frame_size
        if instance.povbench_condition.uses_exploration_frames:
            name = self.prompts.frames
            if name is None:
                raise ValueError(
                    f"prompts {self.prompts.name!r} are for Given (c) only, not {instance.povbench_condition.label} "
                    f"({instance.povbench_condition.value}): {self.prompts.source}; restrict instances.conditions"
                )
            return fill_sentence(name, instance.sentence, width, height, len(self.shown_frames(instance)))
        assert self.prompts.given is not None  # every family has a Given prompt
        return fill_sentence(self.prompts.given, instance.sentence, width, height)

    def images_for(self, instance: Instance, images: ImageStore) -> list[str]:
        """Hashes of the images shown, in order (the frames as they are)."""
        return shown_images(instance, images, self.shown_frames(instance))

    def answer_spec(self, instance: Instance) -> AnswerSpec:
        """What this strategy asks for, without building the request (``povagent rescore`` uses
        it to re-parse a finished run without touching an image)."""
        return answer_spec(instance, len(self.shown_frames(instance)))

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """One user message (images first, then the prompt) asking for the paper's JSON answer."""
        message = prompt_message(
            instance, self.images_for(instance, images), self.prompt_text(instance), self.prompts.given_label
        )
        return Request(
            messages=(message,), answer=self.answer_spec(instance), generation=self.generation, instance=instance
        )


@hookimpl
def register_strategies(register) -> None:
    """Contribute the basic strategy."""
    register(
        "basic",
        BasicStrategy,
        description="The basic prompt as the authors' runner sent it (A/B: every frame, labelled; C: the labelled observer view)",
    )
