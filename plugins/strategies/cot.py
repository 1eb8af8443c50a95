"""The ``cot`` and ``spatial-cot`` strategies: the paper's chain-of-thought prompts, 1,024 new tokens.

S-CoT is the CoT prompt with Step 4 replaced (the paper's definition), built by filling the CoT
template's ``$step4`` with the other Step 4 text. The paper gives no CoT prompt for Given: a C
instance gets the basic Given prompt, with the longer budget. Single-turn.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.instances import Instance
from povagent.exchange.prompts import frame_values, load_template, render
from povagent_plugins.strategies.basic import BasicStrategy


class CotStrategy(BasicStrategy):
    """CoT prompt (Inferred/Stated); options as :class:`BasicStrategy`, ``max_tokens`` 1024."""

    default_max_tokens = 1024
    #: The template holding this strategy's Step 4.
    step4_template = "cot_step4"

    def prompt_text(self, instance: Instance) -> str:
        """The CoT template with this strategy's Step 4 (basic Given prompt for C)."""
        if not instance.condition.uses_exploration_frames:
            return super().prompt_text(instance)
        width, height = instance.frame_size
        values = frame_values(width, height, len(instance.frames))
        return render("cot_frames", sentence=instance.sentence, step4=load_template(self.step4_template), **values)


class SpatialCotStrategy(CotStrategy):
    """Spatial-CoT: the CoT prompt with the structured Step 4 (4a-4e)."""

    step4_template = "spatial_cot_step4"


@hookimpl
def register_strategies(register) -> None:
    """Contribute the CoT and Spatial-CoT strategies."""
    register("cot", CotStrategy, description="The paper's CoT prompt (A/B); basic Given prompt for C; 1024 tokens")
    register(
        "spatial-cot",
        SpatialCotStrategy,
        description="The paper's Spatial-CoT prompt: CoT with Step 4 replaced (A/B); basic Given prompt for C; 1024 tokens",
    )
