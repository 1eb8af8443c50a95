"""Loading and filling prompt templates (povagent/exchange/prompts.py)."""

from __future__ import annotations

import pytest

from povagent.exchange.prompts import frame_values, load_template, render

TEMPLATES = [
    "basic_frames", "basic_given", "coordinate_system", "cot_frames", "cot_step4", "spatial_cot_step4",
    "o_plot_note", "oa_plot_note", "molmopoint_frames", "molmopoint_given", "robopoint_given",
    "appendix_basic_frames", "appendix_basic_given", "appendix_cot_frames", "appendix_cot_step4",
    "appendix_spatial_cot_step4",
]


@pytest.mark.parametrize("name", TEMPLATES)
def test_every_template_loads_without_its_final_newline(name):
    text = load_template(name)
    assert text and not text.endswith("\n")


def test_the_txt_suffix_is_optional():
    assert load_template("basic_given.txt") == load_template("basic_given")


def test_an_unknown_template_names_itself():
    with pytest.raises(FileNotFoundError, match=r"no_such_prompt.txt"):
        load_template("no_such_prompt")


def test_a_missing_placeholder_value_is_an_error():
    with pytest.raises(KeyError, match="sentence"):
        render("basic_given", **frame_values(512, 512))


def test_frame_values_fill_the_last_index_pixel_and_coordinate_paragraph():
    values = frame_values(640, 480, 12)
    paragraph = values.pop("coordinate_system")
    assert values == {"width": 640, "height": 480, "max_x": 639, "max_y": 479, "n_images": 12, "last_index": 11}
    assert "x=639 is the right edge" in paragraph and "Image size: 640 x 480 pixels." in paragraph
    assert paragraph.endswith("Valid range: x \u2208 [0, 639], y \u2208 [0, 479].")
