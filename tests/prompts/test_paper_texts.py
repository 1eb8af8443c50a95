"""The ``appendix`` prompt variant (``prompts: appendix``) is the paper's appendix, word for word.

The default prompts are the authors' runner's (``test_runner_texts.py``); the appendix is a typeset
summary of them, kept as a named variant to compare with.

The expected texts below were transcribed by hand from the appendix "Evaluation Prompts"
(N = 30 frames, 512x512, the sentence below), independently of the template files, following
the LaTeX-to-text rules of ``prompts/README.md``. They are also derived mechanically, by those
rules, from ``paper_prompts.tex`` (the appendix's LaTeX copied verbatim) and compared, so a
drift in either the hand transcription or the templates fails. That the copy is the paper's,
byte for byte, is checked against the paper's own source by ``benchmarks/paper_fidelity.py``
(CI runs it where the source is present; a user's clone has no such file).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from povagent.dataset.release_models import Condition
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.cot import CotStrategy, SpatialCotStrategy
from povagent_plugins.strategies.markers import ObserverAnchorPlotStrategy, ObserverPlotStrategy

SENTENCE = "While watering the plant, I noticed my keys to the left of the sofa."

BASIC_FRAMES = (
    "You are the intelligent brain system of a home-assistance robot. You are given first-person perspective images captured during the robot's exploration of "
    "a home.\n"
    "The 30 images above (labeled Image 0 through Image 29) were all taken during exploration of the same single-story house. Each image is preceded by its "
    "label (\"Image 0:\", \"Image 1:\", etc.).\n"
    "Sentence: \"While watering the plant, I noticed my keys to the left of the sofa.\"\n"
    "The resident has asked the robot to retrieve an object and is describing where they last saw it. Your mission is to predict, as accurately as possible, "
    "where that object is located, based on the resident's description in the sentence above.\n"
    "\n"
    "Task:\n"
    "1. Select the image (0 to 29) that best represents the scene described in the sentence\u2014the image where both the observer's furniture and the "
    "reference landmark are most clearly visible.\n"
    "2. In the selected image, predict the center of the target object as pixel coordinates. The target object may not actually be visible in the image. Based "
    "on the sentence, predict as faithfully and accurately as possible where the center of the object WOULD be located.\n"
    "Image coordinate system: origin [0,0] at the top-left corner; x-axis points right (x \u2208 [0,511]); y-axis points down (y \u2208 [0,511]); image size "
    "512\u00d7512 pixels.\n"
    "IMPORTANT: When predicting coordinates, pay close attention to the origin position and axis directions, and ensure all values fall within the valid "
    "range.\n"
    "Output ONLY valid JSON, no other text:\n"
    "{\"selected_image\": <integer 0-29>, \"x\": <integer 0-511>, \"y\": <integer 0-511>}"
)

BASIC_GIVEN = (
    "You are the intelligent brain system of a home-assistance robot.\n"
    "Sentence: \"While watering the plant, I noticed my keys to the left of the sofa.\"\n"
    "The resident has asked the robot to retrieve an object and is describing where they last saw it. Your mission is to predict, as accurately as possible, "
    "where that object is located\u2014based on the resident's description in the sentence above.\n"
    "The image provided shows the target scene from the perspective of the resident at the moment they spotted the target object.\n"
    "\n"
    "Task: Based on the sentence, predict the center of the target object as pixel coordinates. The target object may not actually be visible in the image. "
    "Based on the sentence, predict as faithfully and accurately as possible where the center of the object WOULD be located.\n"
    "Image coordinate system: origin [0,0] at the top-left corner; x-axis points right (x \u2208 [0,511]); y-axis points down (y \u2208 [0,511]); image size "
    "512\u00d7512 pixels.\n"
    "IMPORTANT: When predicting coordinates, pay close attention to the origin position and axis directions, and ensure all values fall within the valid "
    "range.\n"
    "Output ONLY valid JSON, no other text:\n"
    "{\"x\": <integer 0-511>, \"y\": <integer 0-511>}"
)

COT_FRAMES = (
    "You are the intelligent brain system of a home-assistance robot. You are given first-person perspective images captured during the robot's exploration of "
    "a home.\n"
    "The 30 images above (labeled Image 0 through Image 29) were all taken during exploration of the same single-story house. Each image is preceded by its "
    "label (\"Image 0:\", \"Image 1:\", etc.).\n"
    "Sentence: \"While watering the plant, I noticed my keys to the left of the sofa.\"\n"
    "The resident has asked the robot to retrieve an object and is describing where they last saw it. Your mission is to predict, as accurately as possible, "
    "where that object is located, based on the resident's description in the sentence above.\n"
    "\n"
    "Think step by step:\n"
    "\n"
    "Step 1 \u2014 Image selection. Among the 30 images, identify the one that best represents the scene described in the sentence\u2014the image where both "
    "the furniture the observer was working with and the spatial landmark mentioned in the sentence are most clearly visible. Note its index.\n"
    "Step 2 \u2014 Observer position. In the selected image, identify the furniture the observer was working with at the time. Note roughly where it appears "
    "and what direction the observer would be facing.\n"
    "Step 3 \u2014 Anchor landmark. Identify the spatial landmark mentioned in the sentence in the selected image.\n"
    "Step 4 \u2014 Spatial reasoning. Based on the spatial relationship described in the sentence, estimate where the target object would be located in the "
    "selected image.\n"
    "Step 5 \u2014 Conclusion. State your selected image index and final coordinate estimate.\n"
    "\n"
    "Image coordinate system: origin [0,0] at the top-left corner; x-axis points right (x \u2208 [0,511]); y-axis points down (y \u2208 [0,511]); image size "
    "512\u00d7512 pixels.\n"
    "IMPORTANT: When predicting coordinates, pay close attention to the origin position and axis directions, and ensure all values fall within the valid "
    "range.\n"
    "Write your step-by-step reasoning freely. End your response with ONLY the final JSON on the last line:\n"
    "{\"selected_image\": <integer 0-29>, \"x\": <integer 0-511>, \"y\": <integer 0-511>}"
)

COT_STEP4 = (
    "Step 4 \u2014 Spatial reasoning. Based on the spatial relationship described in the sentence, "
    "estimate where the target object would be located in the selected image."
)

SPATIAL_STEP4 = (
    "Step 4 \u2014 Spatial reasoning\n"
    "4a) Directional frame. Define the viewing direction as from the observer's furniture toward the anchor object. Interpret spatial relations from the "
    "observer's perspective while facing the anchor object:\n"
    "- LEFT / RIGHT: object lies to the left or right of the anchor object\n"
    "- FRONT: object is closer to the observer than the anchor object\n"
    "- ON TOP: object is resting on or above the anchor object\n"
    "- OTHER: relation does not clearly fit the above categories\n"
    "4b) Anchor coordinate. Estimate the pixel coordinate (x, y) of the anchor object.\n"
    "4c) Scene inventory. Identify two or three nearby visible objects around the anchor object. For each object, provide: object name or description; spatial "
    "relation to the anchor object; estimated pixel coordinate (x, y).\n"
    "4d) Target relation. Determine the spatial relation of the target object relative to the anchor object.\n"
    "4e) Target coordinate estimation. Estimate the target pixel coordinate using the anchor object coordinate, nearby object coordinates, and spacing and "
    "scale cues."
)

SPATIAL_COT_FRAMES = COT_FRAMES.replace(COT_STEP4, SPATIAL_STEP4)


class _Stub:
    """Just what ``prompt_text`` reads from an instance."""

    def __init__(self, condition: Condition, n_frames: int = 30) -> None:
        self.condition = self.povbench_condition = condition
        self.sentence = SENTENCE
        self.frames = tuple(range(n_frames if condition.uses_exploration_frames else 1))
        self.frame_size = (512, 512)


INFERRED, GIVEN = _Stub(Condition.INFERRED), _Stub(Condition.GIVEN)


def test_basic_frames_prompt_is_the_papers():
    assert BasicStrategy(prompts="appendix").prompt_text(INFERRED) == BASIC_FRAMES


def test_stated_uses_the_same_prompt_as_inferred():
    assert BasicStrategy(prompts="appendix").prompt_text(_Stub(Condition.STATED)) == BASIC_FRAMES


def test_basic_given_prompt_is_the_papers():
    assert BasicStrategy(prompts="appendix").prompt_text(GIVEN) == BASIC_GIVEN


def test_cot_prompt_is_the_papers():
    assert CotStrategy(prompts="appendix").prompt_text(INFERRED) == COT_FRAMES


def test_spatial_cot_prompt_is_cot_with_step4_replaced():
    assert COT_STEP4 in COT_FRAMES and SPATIAL_COT_FRAMES != COT_FRAMES
    assert SpatialCotStrategy(prompts="appendix").prompt_text(INFERRED) == SPATIAL_COT_FRAMES


@pytest.mark.parametrize("strategy", [ObserverPlotStrategy, ObserverAnchorPlotStrategy])
def test_marker_strategies_use_the_basic_prompt_text(strategy):
    assert strategy(prompts="appendix").prompt_text(INFERRED) == BASIC_FRAMES
    assert strategy(prompts="appendix").prompt_text(GIVEN) == BASIC_GIVEN


def test_placeholders_follow_the_frame_count_and_size():
    stub = _Stub(Condition.INFERRED, n_frames=12)
    stub.frame_size = (640, 480)
    text = BasicStrategy(prompts="appendix").prompt_text(stub)
    assert "The 12 images above (labeled Image 0 through Image 11)" in text
    assert "(x \u2208 [0,639]); y-axis points down (y \u2208 [0,479]); image size 640\u00d7480 pixels." in text
    assert text.endswith('{"selected_image": <integer 0-11>, "x": <integer 0-639>, "y": <integer 0-479>}')


def test_a_dollar_sign_in_the_sentence_is_kept_verbatim():
    stub = _Stub(Condition.GIVEN)
    stub.sentence = "I left $5 and $width next to the lamp."
    assert 'Sentence: "I left $5 and $width next to the lamp."' in BasicStrategy(prompts="appendix").prompt_text(stub)


# -- against the paper's LaTeX ----------------------------------------------------------------------
#: The appendix "Evaluation Prompts", copied verbatim from the paper's .tex (always present).
PROMPTS_TEX = Path(__file__).resolve().parent / "paper_prompts.tex"
HEADINGS = {
    "basic-frames": "\\paragraph{Basic prompt (Inferred / Stated).}",
    "basic-given": "\\paragraph{Basic prompt (Given).}",
    "cot": "\\paragraph{CoT prompt (Inferred / Stated).}",
    "spatial-step4": "\\paragraph{Spatial-CoT prompt (Inferred / Stated).}",
}


def _box_after(tex: str, heading: str) -> str:
    start = tex.index(heading)
    begin = tex.index("\\begin{tcolorbox}", start)
    body_start = tex.index("\n", begin) + 1
    return tex[body_start : tex.index("\\end{tcolorbox}", body_start)]


def _unwrap(text: str, command: str, transform=lambda s: s) -> str:
    """Replace ``\\command{...}`` (balanced braces) by its transformed content."""
    token = f"\\{command}{{"
    while (i := text.find(token)) >= 0:
        depth, j = 1, i + len(token)
        while depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0) if text[j - 1] != "\\" else 0
            j += 1
        text = text[:i] + transform(text[i + len(token) : j - 1]) + text[j:]
    return text


def latex_to_text(body: str) -> str:
    """The README's LaTeX-to-text rules, applied to a prompt box of the paper."""
    s = body.replace("\\small", "")
    s = " ".join(line.strip() for line in s.splitlines())  # LaTeX: a newline is a space
    s = s.replace("\\\\[0.5em]", "\n\x01\n")
    s = re.sub(r"\\\\(\[[0-9.]+em\])?", "\n", s)
    n = 0

    def enum_item(_m: re.Match) -> str:
        nonlocal n
        n += 1
        return f"\n{n}. "

    s = re.sub(r"\\begin\{enumerate\}\[[^\]]*\]", "\n", s)
    s = re.sub(r"\\end\{enumerate\}", "\n", s)
    if "\\begin{itemize}" in s:
        s = re.sub(r"\\begin\{itemize\}\[[^\]]*\]", "\n", s)
        s = s.replace("\\end{itemize}", "\n")
        s = re.sub(r"\\item\s*", "\n- ", s)
    s = re.sub(r"\\item\s*", enum_item, s)
    s = _unwrap(s, "textsc", str.upper)
    for cmd in ("textbf", "textit", "texttt"):
        s = _unwrap(s, cmd)
    s = s.replace("``", '"').replace("''", '"').replace("---", "\u2014")
    s = s.replace("\\textless ", "<").replace("\\textgreater", ">")
    s = s.replace("\\{", "{").replace("\\}", "}").replace("\\_", "_").replace("~", " ")
    s = s.replace("$x\\in[0,W\\!-\\!1]$", "x \u2208 [0,W-1]").replace("$y\\in[0,H\\!-\\!1]$", "y \u2208 [0,H-1]")
    s = s.replace("$W\\times H$", "W\u00d7H").replace("$-1$", "-1")
    s = re.sub(r"\$([^$]*)\$", r"\1", s)
    s = re.sub(r"\{([A-Z /]+)\}", r"\1", s)  # {LEFT / RIGHT}: grouping braces only
    lines = [re.sub(r"\s+", " ", line).strip() for line in s.split("\n")]
    text = "\n".join(line for line in lines if line).replace("\x01", "")
    return text


def fill(text: str, n: int = 30, w: int = 512, h: int = 512) -> str:
    """The paper's placeholders filled as at run time."""
    for a, b in (
        ("0-(N-1)", f"0-{n - 1}"), ("0-(W-1)", f"0-{w - 1}"), ("0-(H-1)", f"0-{h - 1}"),
        ("N-1", str(n - 1)), ("W-1", str(w - 1)), ("H-1", str(h - 1)), ("W\u00d7H", f"{w}\u00d7{h}"),
        ("The N images", f"The {n} images"), ("the N images", f"the {n} images"), ("<sentence>", SENTENCE),
    ):
        text = text.replace(a, b)
    return text


@pytest.mark.parametrize(
    "box, expected",
    [("basic-frames", BASIC_FRAMES), ("basic-given", BASIC_GIVEN), ("cot", COT_FRAMES)],
)
def test_transcription_matches_the_papers_latex(box, expected):
    tex = PROMPTS_TEX.read_text(encoding="utf-8")
    assert fill(latex_to_text(_box_after(tex, HEADINGS[box]))) == expected


def test_spatial_step4_matches_the_papers_latex():
    tex = PROMPTS_TEX.read_text(encoding="utf-8")
    assert latex_to_text(_box_after(tex, HEADINGS["spatial-step4"])) == SPATIAL_STEP4


def test_the_spatial_cot_box_replaces_exactly_the_cot_step4():
    """The paper: S-CoT is "identical to the CoT prompt above, except that Step 4 is replaced"."""
    tex = PROMPTS_TEX.read_text(encoding="utf-8")
    cot = latex_to_text(_box_after(tex, HEADINGS["cot"]))
    assert fill(cot).count(COT_STEP4) == 1
