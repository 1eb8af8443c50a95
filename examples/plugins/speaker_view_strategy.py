"""A strategy plugin in a few lines: the built-in ``basic`` strategy plus one reminder.

It extends :class:`BasicStrategy` and overrides only ``prompt_text``; the frames, their labels,
the answer format and the options (``max_tokens``, ``prompts``, ``max_frames``...) stay the basic
strategy's. In a pipeline YAML::

    plugins: [speaker_view_strategy.py]     # read from the YAML file's folder
    strategy: speaker-view
"""

from povagent import hookimpl
from povagent.dataset.instances import Instance
from povagent_plugins.strategies.basic import BasicStrategy

REMINDER = "Left, right and front are meant from where the speaker stood, not from the camera."


class SpeakerViewStrategy(BasicStrategy):
    """The basic prompt, then a reminder that directions are the speaker's."""

    def prompt_text(self, instance: Instance) -> str:
        """The basic prompt's text with the reminder as its last line."""
        return f"{super().prompt_text(instance)}\n{REMINDER}"


@hookimpl
def register_strategies(register):
    """Contribute the speaker-view strategy."""
    register("speaker-view", SpeakerViewStrategy, description="The basic prompt plus a reminder that directions are the speaker's")
