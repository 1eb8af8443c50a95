"""The ``choice`` strategy: images, then a question and its labelled options, asking for a label.

Single-turn. The wording around the question is a *profile* (:func:`prompt_profiles`: ``plain``
and each registered dataset format's), named by
the instance's question (``ChoiceQuestion.profile``) unless the ``profile`` option overrides it:
each perspective-taking set is asked in its own published wording, and a generated relation
task in povagent's ``plain`` one. The images are the instance's frames in order (a set's images
as its records list them).

Options: ``max_tokens`` (default 256; ``null`` sends no limit), ``temperature`` (default: the
backend's), ``profile`` (default: each question's own).
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.spec import AnswerSpec, choice_answer_schema
from povagent.dataset.formats import PromptProfile, registered_formats
from povagent.dataset.instances import Instance
from povagent.errors import PluginError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Part, Request, TextPart
from povagent.interfaces import LoadedPlugins, Strategy
from povagent.plugins import PluginHost
from povagent_plugins.strategies.basic import generation_options

#: How a set words a multiple-choice prompt: the text after the images (a dataset format's
#: :attr:`~povagent.dataset.formats.DatasetFormat.prompt_profile`).
ChoiceProfile = PromptProfile


def plain_text(question: ChoiceQuestion) -> str:
    """The question, the options one per line (``A. left``), and the instruction to answer with a label."""
    return f"{question.question}\n{question.options_block()}\nAnswer with the option's letter from the given choices directly."


#: povagent's own prompt profile; every other is a registered dataset format's (:func:`prompt_profiles`).
PLAIN = ChoiceProfile("plain", plain_text, "povagent's wording (the instruction lmms-eval's multiple-choice tasks append)")


def prompt_profiles(host: PluginHost | None = None) -> dict[str, ChoiceProfile]:
    """Prompt profiles by name: ``plain``, then each registered dataset format's (a set's reader
    names its format's profile in each question), from ``host`` (default: the process's)."""
    if host is None:
        from povagent.plugins import get_plugin_host

        host = get_plugin_host()
    found = {PLAIN.name: PLAIN}
    for dataset_format in registered_formats(host).values():
        if dataset_format.prompt_profile is not None:
            found.setdefault(dataset_format.prompt_profile.name, dataset_format.prompt_profile)
    return found


#: Where an interleaved profile's text places an image.
IMAGE_MARKER = "<image>"


def choice_answer_spec(instance: Instance) -> AnswerSpec:
    """The answer asked: one of the question's labels."""
    question = instance.question
    if question is None:
        raise ValueError(f"instance {instance.id} asks no multiple-choice question: use a point strategy")
    width, height = instance.frame_size
    key = (question.options, width, height, len(instance.frames))
    spec = _SPECS.get(key)
    if spec is None:
        spec = AnswerSpec(
            schema=choice_answer_schema(question.labels), width=width, height=height, n_frames=len(instance.frames), asks_frame=False, choices=question.options
        )
        if len(_SPECS) < _MAX_SPECS:
            _SPECS[key] = spec
    return spec


#: The answer specs made so far, by options, frame size and frame count: a set's 10,000
#: questions ask a few dozen (a spec is frozen; made and validated once each).
_SPECS: dict[tuple[tuple[tuple[str, str], ...], int, int, int], AnswerSpec] = {}
_MAX_SPECS = 4096


class ChoiceStrategy(Strategy):
    """The question's images, then its profile's text (see the module docstring)."""

    answer_type = "choice"
    default_parser = "choice"

    def __init__(self, max_tokens: int | None = 256, temperature: float | None = None, profile: str | None = None) -> None:
        if max_tokens is not None and (not isinstance(max_tokens, int) or isinstance(max_tokens, bool) or max_tokens < 1):
            raise ValueError(f"strategy option max_tokens must be a positive integer or null, got {max_tokens!r}")
        self.generation = generation_options(max_tokens, temperature)
        if profile is not None and not isinstance(profile, str):
            raise ValueError(f"strategy option profile must be a prompt profile's name, got {profile!r}")
        self.profile = profile
        # the process's profiles until the plugin host hands over its own (a pipeline's plugins'
        # formats too), which is where an unknown profile is refused
        self.profiles = prompt_profiles()

    def use_plugins(self, host: LoadedPlugins) -> None:
        """The prompt profiles are those of the formats ``host`` registers (a pipeline's plugins too)."""
        if isinstance(host, PluginHost):
            self.profiles = prompt_profiles(host)
            if self.profile is not None and self.profile not in self.profiles:
                raise PluginError(f"strategy option profile must be one of {', '.join(sorted(self.profiles))}, got {self.profile!r}")

    def identity(self) -> dict[str, Any]:
        """Nothing beyond the YAML decides the rows."""
        return {}

    def profile_of(self, instance: Instance) -> tuple[ChoiceProfile, ChoiceQuestion]:
        """The profile the instance is asked in (the strategy's option, else the question's
        own) and its question."""
        question = instance.question
        if question is None:
            raise ValueError(f"instance {instance.id} asks no multiple-choice question: use a point strategy")
        return self.named_profile(instance, question.profile), question

    def named_profile(self, instance: Instance, own: str) -> ChoiceProfile:
        """The profile the strategy's option names, else ``own`` (the question's)."""
        name = self.profile or own
        profile = self.profiles.get(name)
        if profile is None:
            raise ValueError(f"instance {instance.id} names prompt profile {name!r}, which no strategy knows")
        return profile

    def prompt_text(self, instance: Instance) -> str:
        """The text after the images (an interleaved profile's still holds its image markers)."""
        profile, question = self.profile_of(instance)
        return profile.text(question)

    def answer_spec(self, instance: Instance) -> AnswerSpec:
        """One of the question's labels."""
        return choice_answer_spec(instance)

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """One user message: every image of the instance in order, then the question; an
        interleaved profile puts image *k* at the text's *k*-th ``<image>`` marker instead
        (each text piece stripped, empty pieces left out, as lmms-eval's MindCube task does); a
        question with no marker (MindCube's raw records) has its images first, as MindCube's
        own inference places them."""
        profile, question = self.profile_of(instance)  # (once: the text and the layout both follow it)
        text = profile.text(question) if type(self).prompt_text is ChoiceStrategy.prompt_text else self.prompt_text(instance)
        image_parts = [ImagePart(images.add_file(frame.file).image_hash, label=f"Image {frame.index}") for frame in instance.frames]
        parts: list[Part] = []
        if profile.interleaved and IMAGE_MARKER in text:
            pieces = text.split(IMAGE_MARKER)
            if len(pieces) - 1 != len(image_parts):
                raise ValueError(f"instance {instance.id}: its question has {len(pieces) - 1} {IMAGE_MARKER} marker(s) for {len(image_parts)} image(s)")
            for k, piece in enumerate(pieces):
                if piece.strip():
                    parts.append(TextPart(piece.strip()))
                if k < len(image_parts):
                    parts.append(image_parts[k])
        else:
            parts = [*image_parts, TextPart(text)]
        return Request(messages=(Message("user", tuple(parts)),), answer=self.answer_spec(instance), generation=self.generation, instance=instance)


@hookimpl
def register_strategies(register) -> None:
    """Contribute the choice strategy."""
    register("choice", ChoiceStrategy, description="Multiple choice: the images, the question and its labelled options; answer a label")
