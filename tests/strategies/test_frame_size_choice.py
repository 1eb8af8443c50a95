"""A labelled choice (docs/explanation/official.md, "Frame sizes"): the prompt's pixel range and the
parser's range check use the size of the frame the model is shown.

The authors' runners used fixed or borrowed sizes: ``run_vlm_eval.py`` states 512x512 in the
A/B prompt and checks A/B and Given answers against 512x512; the ablation runners state the
*observer camera's* size for the exploration frames. On the release (every image 512x512) all of
these are the same number; on a 640x480 set they are not, and povagent keeps each frame's own
(an observer view's is its camera's ``screen_width``/``screen_height``; exploration frames are
loaded at ``load_dataset(frame_size=...)``, 512x512 unless said).
"""

from __future__ import annotations

import pytest

from povagent.dataset import load_dataset
from povagent.exchange.images import ImageStore
from povagent.plugins import get_plugin_host
from povagent.testing.pytest_plugin import write_release


@pytest.fixture(scope="module")
def wide_set(tmp_path_factory):
    root = write_release(tmp_path_factory.mktemp("wide") / "ds", houses=1, pairs=1, frames=2, size=(640, 480))
    # exploration frames carry no size in their log records: a set of 640x480 frames says so
    return load_dataset(root, frame_size=(640, 480))


@pytest.mark.parametrize(("strategy", "condition"), [("basic", "a"), ("basic", "c"), ("cot", "b")])
def test_the_prompt_and_the_parse_range_are_the_shown_frames_own_size(wide_set, strategy, condition):
    inst = wide_set.instances(conditions=[condition])[0]
    assert inst.frame_size == (640, 480)
    request = get_plugin_host().create("strategy", strategy, {}).build(inst, ImageStore())
    text = "".join(getattr(part, "text", "") for m in request.messages for part in m.parts)
    assert '"x": <integer 0-639>' in text and '"y": <integer 0-479>' in text
    assert (request.answer.width, request.answer.height) == (640, 480)


def test_the_official_parser_checks_the_range_of_the_shown_frame(wide_set):
    """Two answers, the last out of a 640x480 frame: the earlier, in range, wins. Checked
    against 512x512 (the basic runner's constant) the earlier would be out of range too."""
    inst = wide_set.instances(conditions=["c"])[0]
    request = get_plugin_host().create("strategy", "basic", {}).build(inst, ImageStore())
    parsed = get_plugin_host().create("parser", "official", {}).parse('{"x": 600, "y": 470} then {"x": 700, "y": 10}', request.answer)
    assert (parsed.x, parsed.y) == (600.0, 470.0)
