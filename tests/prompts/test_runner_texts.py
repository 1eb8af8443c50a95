"""Every prompt sent is the authors' runner's string, byte for byte.

The expected texts are written out here from the runner's scripts as read in
``mimo-owl/povbench-eval`` (``evaluation/run_vlm_eval.py``: ``_coord_description``,
``_prompt_ab``, ``_prompt_c``, ``_prompt_ab_molmo``, ``_prompt_c_molmo``,
``_prompt_c_robopoint``; ``run_vlm_eval_ab1.py`` / ``ab2.py``: the notes on the marks and where
they go; ``ab3.py`` / ``ab4.py``: the CoT and S-CoT prompts), independently of the template
files under ``prompts/``: a template that drifts by one byte fails here. The runner's quirks are
part of the protocol and kept: no space in "saw it.Your mission" (``_prompt_ab`` and
``_prompt_ab_molmo``), a space before the blank line after CoT Step 3, S-CoT's FRONT, ON TOP and
OTHER bullets run together on one line, trailing spaces of the notes.
"""

from __future__ import annotations

import pytest

from povagent.dataset.release_models import Condition
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, TextPart
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.cot import CotStrategy, SpatialCotStrategy
from povagent_plugins.strategies.markers import ObserverAnchorPlotStrategy, ObserverPlotStrategy

DASH = "\u2014"


# -- the runner's texts, as read ------------------------------------------------------------------
def coordinate_block(w: int, h: int) -> str:
    return (
        "Image coordinate system:\n"
        "  - Origin [x=0, y=0] is the TOP-LEFT corner of the image.\n"
        f"  - x-axis points RIGHT: x=0 is the left edge, x={w - 1} is the right edge.\n"
        f"  - y-axis points DOWN:  y=0 is the top edge,  y={h - 1} is the bottom edge.\n"
        f"  - Image size: {w} x {h} pixels.\n"
        f"  - Valid range: x \u2208 [0, {w - 1}], y \u2208 [0, {h - 1}]."
    )


IMPORTANT = (
    "IMPORTANT: When predicting coordinates, pay close attention to the origin position and "
    "axis directions, and ensure all values fall within the valid range."
)
WOULD = (
    "The target object may not actually be visible in the image. Based on the sentence, predict as "
    "faithfully and accurately as possible where the center of the object WOULD be located."
)


def frames_intro(sentence: str, n: int) -> str:
    return (
        "You are the intelligent brain system of a home-assistance robot. You are given first-person "
        "perspective images captured during the robot's exploration of a home.\n\n"
        f"The {n} images above (labeled Image 0 through Image {n - 1}) were all taken during exploration "
        'of the same single-story house. Each image is preceded by its label ("Image 0:", "Image 1:", etc.).\n\n'
        f'Sentence: "{sentence}"\n\n'
    )


def runner_ab(sentence: str, n: int, w: int = 512, h: int = 512, point_directive: bool = False) -> str:
    """``_prompt_ab`` (``point_directive``: ``_prompt_ab_molmo``)."""
    text = frames_intro(sentence, n) + (
        "The resident has asked the robot to retrieve an object and is describing where they last saw it."
        "Your mission is to predict, as accurately as possible, where that object is located, based on the "
        "resident's description in the sentence above.\n\n"
        "Task:\n"
        f"1. Select the image (0 to {n - 1}) that best represents the scene described in the sentence {DASH} the "
        "image where both the observer's furniture and the reference landmark are most clearly visible.\n"
    )
    if point_directive:
        return text + f"2. In the selected image, predict the center of the target object.\n   {WOULD}\n\nPoint to the center of the target object."
    return text + (
        f"2. In the selected image, predict the center of the target object as pixel coordinates.\n   {WOULD}\n\n"
        f"{coordinate_block(w, h)}\n\n{IMPORTANT}\n\n"
        "Output ONLY valid JSON, no other text:\n"
        f'{{"selected_image": <integer 0-{n - 1}>, "x": <integer 0-{w - 1}>, "y": <integer 0-{h - 1}>}}'
    )


def given_intro(sentence: str) -> str:
    return (
        "You are the intelligent brain system of a home-assistance robot.\n\n"
        f'Sentence: "{sentence}"\n\n'
        "The resident has asked the robot to retrieve an object and is describing where they last saw it. "
        f"Your mission is to predict, as accurately as possible, where that object is located {DASH} based on "
        "the resident's description in the sentence above.\n\n"
        "The image provided shows the target scene from the perspective of the resident at the moment they "
        "spotted the target object.\n\n"
    )


def runner_c(sentence: str, w: int = 512, h: int = 512) -> str:
    """``_prompt_c``."""
    return given_intro(sentence) + (
        f"Task: Based on the sentence, predict the center of the target object as pixel coordinates.\n{WOULD}\n\n"
        f"{coordinate_block(w, h)}\n\n{IMPORTANT}\n\n"
        "Output ONLY valid JSON, no other text:\n"
        f'{{"x": <integer 0-{w - 1}>, "y": <integer 0-{h - 1}>}}'
    )


def runner_c_molmo(sentence: str) -> str:
    """``_prompt_c_molmo``."""
    return given_intro(sentence) + (
        f"Task: Based on the sentence, predict the center of the target object.\n{WOULD}\n\n"
        "Point to the center of the target object."
    )


def runner_c_robopoint(sentence: str) -> str:
    """``_prompt_c_robopoint``."""
    return given_intro(sentence) + (
        f"Task: Based on the sentence, predict the center of the target object.\n{WOULD}\n\n"
        "Image coordinate system:\n"
        "  - Origin (0, 0) is the TOP-LEFT corner; (1, 1) is the BOTTOM-RIGHT corner.\n"
        "  - x increases to the RIGHT; y increases DOWNWARD.\n"
        "  - Coordinates are normalized to the range [0, 1].\n\n"
        f"{IMPORTANT}\n\n"
        "Your answer should be formatted as a list of tuples, i.e. [(x1, y1), (x2, y2), ...], where each tuple "
        "contains the x and y coordinates of a point. The coordinates should be between 0 and 1, indicating the "
        "normalized pixel locations of the points in the image."
    )


OBSERVER_NOTE = (
    "In some images, a red circle marks the observer's furniture (the object they were working with at the "
    "moment they saw the target object). "
)
ANCHOR_NOTE = (
    "a blue rectangle marks the anchor object mentioned in the sentence (the landmark used to describe where "
    "the target object is located). "
)


def runner_marked(sentence: str, n: int, anchor: bool) -> str:
    """``ab1`` / ``ab2``: ``_prompt_ab`` with the note on its own line after the label sentence."""
    note = OBSERVER_NOTE + ("In some images, " + ANCHOR_NOTE if anchor else "")
    head = 'Each image is preceded by its label ("Image 0:", "Image 1:", etc.).\n'
    before, after = runner_ab(sentence, n).split(head)
    return before + head + note + "\n" + after


COT_STEP4 = (
    f"Step 4 {DASH} Spatial reasoning: Based on the spatial relationship described in the sentence, estimate "
    "where the target object would be located in the selected image."
)
SPATIAL_STEP4 = (
    f"Step 4 {DASH} Spatial reasoning:\n"
    "  4a) Directional frame: Define the viewing direction as from the observer's furniture (Step 2) toward the "
    "anchor object (Step 3). Use the following spatial relations, all from the observer's perspective when facing "
    "the anchor object:\n"
    "      - LEFT / RIGHT: the object is to the left or right side of the anchor object\n"
    "      - FRONT: the object is closer to the observer than the anchor object "
    "      - ON TOP: the object is physically resting on or above the anchor object "
    "      - OTHER: the spatial relation does not clearly fit any of the above (e.g., behind the anchor, "
    "diagonally distant)\n\n"
    "  4b) Anchor coordinate: Estimate the pixel coordinate (x, y) of the anchor object in the image.\n\n"
    "  4c) Scene inventory: Identify two or three objects that are visible in the selected image and closest to "
    "the anchor object, excluding the observer's furniture. For each object, state:\n"
    "      - Its name or brief description\n"
    "      - Its spatial relation to the anchor object (LEFT, RIGHT, FRONT, ON TOP, or OTHER)\n"
    "      - Its estimated pixel coordinate (x, y) in the image\n\n"
    "  4d) Side identification: Re-read the sentence and determine the spatial relation of the target object to "
    "the anchor object (LEFT, RIGHT, FRONT, or ON TOP).\n\n"
    "  4e) Target location estimate: Using the anchor coordinate from 4b and the surrounding objects' coordinates "
    "from 4c as spatial reference points, estimate the most plausible pixel coordinate for the target object. "
    f"Place it according to the spatial relation identified in 4d {DASH} LEFT, RIGHT, FRONT, or ON TOP relative to "
    f"the anchor {DASH} and use the relative spacing and scale of the inventoried objects to judge and make as "
    "accurate a position estimate as possible."
)


def runner_cot(sentence: str, n: int, step4: str, w: int = 512, h: int = 512) -> str:
    """``ab3`` (``step4`` = COT_STEP4) and ``ab4`` (SPATIAL_STEP4)."""
    return frames_intro(sentence, n) + (
        "The resident has asked the robot to retrieve an object and is describing where they last saw it. "
        "Your mission is to predict, as accurately as possible, where that object is located, based on the "
        "resident's description in the sentence above.\n\n"
        "Think step by step:\n\n"
        f"Step 1 {DASH} Image selection: Among the {n} images, identify the one that best represents the scene "
        f"described in the sentence {DASH} the image where both the furniture the observer was working with and the "
        "spatial landmark mentioned in the sentence are most clearly visible. Note its index.\n\n"
        f"Step 2 {DASH} Observer position: In the selected image, identify the furniture the observer was working "
        "with at the time. Note roughly where it appears and what direction the observer would be facing.\n\n"
        f"Step 3 {DASH} Anchor landmark: Identify the spatial landmark mentioned in the sentence in the selected "
        "image. \n\n"
        f"{step4}\n\n"
        f"Step 5 {DASH} Conclusion: State your selected image index and final coordinate estimate.\n\n"
        f"{coordinate_block(w, h)}\n\n{IMPORTANT}\n\n"
        "Write your step-by-step reasoning freely. End your response with ONLY the final JSON on the last line "
        "(no other text after it):\n"
        f'{{"selected_image": <integer 0-{n - 1}>, "x": <integer 0-{w - 1}>, "y": <integer 0-{h - 1}>}}'
    )


def expected_prompt(strategy: str, instance) -> str:
    """What the runner sent for ``instance`` under ``strategy`` (C: ``_prompt_c`` for every one;
    the authors ran no intervention on Given)."""
    if not instance.condition.uses_exploration_frames:
        return runner_c(instance.sentence)
    n = min(len(instance.frames), 30) if strategy != "basic" else len(instance.frames)
    return {
        "basic": lambda: runner_ab(instance.sentence, n),
        "o-plot": lambda: runner_marked(instance.sentence, n, anchor=False),
        "oa-plot": lambda: runner_marked(instance.sentence, n, anchor=True),
        "cot": lambda: runner_cot(instance.sentence, n, COT_STEP4),
        "spatial-cot": lambda: runner_cot(instance.sentence, n, SPATIAL_STEP4),
    }[strategy]()


STRATEGIES = {
    "basic": BasicStrategy,
    "o-plot": ObserverPlotStrategy,
    "oa-plot": ObserverAnchorPlotStrategy,
    "cot": CotStrategy,
    "spatial-cot": SpatialCotStrategy,
}


# -- the fixture, every strategy x condition -------------------------------------------------------
@pytest.mark.parametrize("condition", ["a", "b", "c"])
@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_every_fixture_prompt_is_the_runners_string(mini_dataset, name, condition):
    instances = mini_dataset.instances(conditions=[condition])
    assert instances
    store = ImageStore()
    for inst in instances:
        text = STRATEGIES[name]().build(inst, store).messages[0].parts[-1].text
        assert text == expected_prompt(name, inst), inst.id


@pytest.mark.parametrize("name", sorted(STRATEGIES))
def test_frames_are_labelled_image_k_and_given_image(mini_dataset, name):
    store = ImageStore()
    inst = mini_dataset.instance("train_house_00000/0/left/b")
    parts = STRATEGIES[name]().build(inst, store).messages[0].parts
    assert [p.text for p in parts[0:-1:2]] == ["Image 0:", "Image 1:", "Image 2:"]
    assert all(isinstance(p, ImagePart) for p in parts[1:-1:2]) and len(parts) == 7
    given = STRATEGIES[name]().build(mini_dataset.instance("train_house_00000/0/left/c"), store).messages[0].parts
    assert isinstance(given[0], TextPart) and given[0].text == "Image:"
    assert isinstance(given[1], ImagePart) and isinstance(given[2], TextPart) and len(given) == 3


def test_the_molmopoint_prompts_are_the_runners(mini_dataset):
    strategy = BasicStrategy(prompts="molmopoint")
    for inst in mini_dataset.instances():
        text = strategy.prompt_text(inst)
        if inst.condition is Condition.GIVEN:
            assert text == runner_c_molmo(inst.sentence), inst.id
        else:
            assert text == runner_ab(inst.sentence, len(inst.frames), point_directive=True), inst.id


def test_the_robopoint_prompt_is_the_runners_and_sent_without_a_label(mini_dataset):
    strategy = BasicStrategy(prompts="robopoint")
    for inst in mini_dataset.instances(conditions=["c"]):
        parts = strategy.build(inst, ImageStore()).messages[0].parts
        assert len(parts) == 2 and isinstance(parts[0], ImagePart)
        assert parts[1].text == runner_c_robopoint(inst.sentence), inst.id


def test_the_robopoint_prompts_have_no_inferred_or_stated_text(mini_dataset):
    with pytest.raises(ValueError, match=r"robopoint.*Given \(c\) only, not Inferred"):
        BasicStrategy(prompts="robopoint").prompt_text(mini_dataset.instance("train_house_00000/0/left/a"))


# -- the runner's quirks, pinned on their own --------------------------------------------------------
def test_the_basic_frames_prompt_keeps_the_runners_missing_space(mini_dataset):
    text = BasicStrategy().prompt_text(mini_dataset.instance("train_house_00000/0/left/a"))
    assert "last saw it.Your mission" in text
    given = BasicStrategy().prompt_text(mini_dataset.instance("train_house_00000/0/left/c"))
    assert "last saw it. Your mission" in given


def test_the_cot_prompts_have_the_space_after_saw_it(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/left/a")
    assert "last saw it. Your mission" in CotStrategy().prompt_text(inst)
    assert "last saw it. Your mission" in SpatialCotStrategy().prompt_text(inst)


class _Stub:
    """Just what ``prompt_text`` reads from an instance."""

    def __init__(self, sentence: str = "I saw it left of the desk.", n_frames: int = 2, size=(512, 512)) -> None:
        self.condition = self.povbench_condition = Condition.INFERRED
        self.sentence = sentence
        self.frames = tuple(range(n_frames))
        self.frame_size = size


def test_the_frame_size_fills_the_coordinate_paragraph():
    inst = _Stub(size=(640, 480))
    assert BasicStrategy().prompt_text(inst) == runner_ab(inst.sentence, 2, 640, 480)
    assert CotStrategy().prompt_text(inst) == runner_cot(inst.sentence, 2, COT_STEP4, 640, 480)


def test_a_dollar_sign_in_the_sentence_is_kept_verbatim():
    sentence = "I left $5 and $width next to the $coordinate_system lamp."
    inst = _Stub(sentence, n_frames=1)
    assert BasicStrategy().prompt_text(inst) == runner_ab(sentence, 1)
    assert CotStrategy().prompt_text(inst) == runner_cot(sentence, 1, COT_STEP4)


@pytest.mark.parametrize("name", ["o-plot", "oa-plot", "cot", "spatial-cot"])
def test_the_ablation_strategies_show_the_first_30_frames(name):
    inst = _Stub(n_frames=42)
    text = STRATEGIES[name]().prompt_text(inst)
    assert "The 30 images above (labeled Image 0 through Image 29)" in text
    assert STRATEGIES[name]().shown_frames(inst) == tuple(range(30))


def test_the_basic_strategy_shows_every_frame_as_the_main_runner():
    inst = _Stub(n_frames=42)
    assert BasicStrategy().prompt_text(inst) == runner_ab(inst.sentence, 42)
    assert BasicStrategy(max_frames=30).prompt_text(inst) == runner_ab(inst.sentence, 30)
