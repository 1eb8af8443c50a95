"""The ``cot`` and ``spatial-cot`` strategies: the chain-of-thought prompts of the authors'
ablation scripts (``run_vlm_eval_ab3.py``, ``ab4.py``), 1,024 new tokens, the first 30 frames.

S-CoT is the CoT prompt with its Step 4 replaced (both scripts share every other line), built by
filling the CoT template's ``$step4`` with the other Step 4 text. The authors ran neither on
Given: a C instance gets the basic Given prompt with the longer budget, outside the paper's
protocol (:meth:`~povagent_plugins.strategies.basic.BasicStrategy.outside_paper_protocol`).
Single-turn.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.instances import Instance
from povagent.dataset.release_models import Condition
from povagent.exchange.prompts import frame_values, load_template, render
from povagent_plugins.strategies.basic import ABLATION_MAX_FRAMES, BasicStrategy


class CotStrategy(BasicStrategy):
    """CoT prompt (Inferred/Stated); options as :class:`BasicStrategy`, ``max_tokens`` 1024."""

    default_max_tokens = 1024
    default_max_frames = ABLATION_MAX_FRAMES
    paper_conditions = (Condition.INFERRED, Condition.STATED)
    #: The prompt-family field naming this strategy's Step 4.
    step4_field = "cot_step4"

    def _check_prompts(self) -> None:
        if not self.prompts.has_interventions:
            raise ValueError(
                f"strategy option prompts: {self.prompts.name!r} has no chain-of-thought prompt "
                "(the authors ran CoT and S-CoT with their standard prompt only); use runner or appendix"
            )

    def prompt_text(self, instance: Instance) -> str:
        """The CoT template with this strategy's Step 4 (the basic Given prompt for C)."""
        if not instance.povbench_condition.uses_exploration_frames:
            return super().prompt_text(instance)
        width, height = instance.frame_size
        values = frame_values(width, height, len(self.shown_frames(instance)))
        step4 = load_template(getattr(self.prompts, self.step4_field))
        template = self.prompts.cot_frames
        assert template is not None  # _check_prompts refused prompt sets without one
        return render(template, sentence=instance.sentence, step4=step4, **values)


class SpatialCotStrategy(CotStrategy):
    """Spatial-CoT: the CoT prompt with the structured Step 4 (4a-4e)."""

    step4_field = "spatial_cot_step4"


@hookimpl
def register_strategies(register) -> None:
    """Contribute the CoT and Spatial-CoT strategies."""
    register(
        "cot",
        CotStrategy,
        description="The authors' CoT prompt (A/B, first 30 frames); 1024 tokens; on C the basic Given prompt (outside the paper's protocol)",
    )
    register(
        "spatial-cot",
        SpatialCotStrategy,
        description="The authors' Spatial-CoT prompt: CoT with Step 4 replaced (A/B, first 30 frames); 1024 tokens; on C outside the paper's protocol",
    )
