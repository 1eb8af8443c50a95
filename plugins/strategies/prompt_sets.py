"""Which prompt templates a strategy fills: the ``prompts`` option of the built-in strategies.

* ``runner`` (default): the texts the authors' runner sent (``mimo-owl/povbench-eval``:
  ``run_vlm_eval.py`` for Basic, ``run_vlm_eval_ab1.py`` .. ``ab4.py`` for the notes of O-Plot
  and O&A-Plot and for CoT and S-CoT). These produced the paper's numbers.
* ``appendix``: the paper appendix's typeset summary of those prompts, transcribed; kept to
  compare with, never the default.
* ``molmopoint``: the runner's MolmoPoint prompts (task text unchanged, output directive "Point
  to the center of the target object."), A/B and C, basic strategy only.
* ``robopoint``: the runner's RoboPoint prompt (task text unchanged, answer asked as a list of
  normalised tuples), Given only, basic strategy only; the observer view is sent without the
  ``Image:`` label (the runner's RoboPoint path put the image token straight before the text).

This module only names templates; filling them is the strategies' job.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PromptSet:
    """The templates of one prompt family (``None``: the family has no such prompt).

    ``frames`` / ``given`` are the basic prompts of A/B and C; ``cot_frames`` the CoT prompt
    with a ``$step4`` placeholder, filled with ``cot_step4`` (CoT) or ``spatial_cot_step4``
    (S-CoT); ``marker_notes`` whether O-Plot and O&A-Plot tell the model what the marks mean
    (the runner's ``ab1``/``ab2`` do, the appendix does not print it); ``given_label`` the text
    part sent before the observer view.
    """

    name: str
    source: str
    frames: str | None
    given: str | None
    cot_frames: str | None = None
    cot_step4: str | None = None
    spatial_cot_step4: str | None = None
    marker_notes: bool = False
    given_label: str | None = "Image:"

    @property
    def has_interventions(self) -> bool:
        """Whether the ablation strategies (markers, CoT, S-CoT) have texts in this family."""
        return self.cot_frames is not None


PROMPT_SETS: dict[str, PromptSet] = {
    "runner": PromptSet(
        name="runner",
        source="the authors' runner (run_vlm_eval.py; run_vlm_eval_ab1.py .. ab4.py)",
        frames="basic_frames",
        given="basic_given",
        cot_frames="cot_frames",
        cot_step4="cot_step4",
        spatial_cot_step4="spatial_cot_step4",
        marker_notes=True,
    ),
    "appendix": PromptSet(
        name="appendix",
        source="the paper's appendix (a typeset summary of the runner's prompts)",
        frames="appendix_basic_frames",
        given="appendix_basic_given",
        cot_frames="appendix_cot_frames",
        cot_step4="appendix_cot_step4",
        spatial_cot_step4="appendix_spatial_cot_step4",
    ),
    "molmopoint": PromptSet(
        name="molmopoint",
        source="the authors' runner's MolmoPoint prompts (_prompt_ab_molmo, _prompt_c_molmo)",
        frames="molmopoint_frames",
        given="molmopoint_given",
    ),
    "robopoint": PromptSet(
        name="robopoint",
        source="the authors' runner's RoboPoint prompt (_prompt_c_robopoint, Given only)",
        frames=None,
        given="robopoint_given",
        given_label=None,
    ),
}

#: The prompt family a strategy uses when its options name none.
DEFAULT_PROMPTS = "runner"


def prompt_set(name: object) -> PromptSet:
    """The prompt family ``name``; ``ValueError`` naming the option and the known names."""
    if not isinstance(name, str) or name not in PROMPT_SETS:
        raise ValueError(f"strategy option prompts: unknown prompt family {name!r}; known: {', '.join(PROMPT_SETS)}")
    return PROMPT_SETS[name]
