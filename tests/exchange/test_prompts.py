"""Loading and filling prompt templates (povagent/exchange/prompts.py)."""

from __future__ import annotations

import pytest

from povagent.exchange.prompts import frame_values, load_template, render


@pytest.mark.parametrize("name", ["basic_frames", "basic_given", "cot_frames", "cot_step4", "spatial_cot_step4"])
def test_every_template_loads_without_its_final_newline(name):
    text = load_template(name)
    assert text and not text.endswith("\n")


def test_the_txt_suffix_is_optional():
    assert load_template("basic_given.txt") == load_template("basic_given")


def test_an_unknown_template_names_itself():
    with pytest.raises(FileNotFoundError, match="no_such_prompt.txt"):
        load_template("no_such_prompt")


def test_a_missing_placeholder_value_is_an_error():
    with pytest.raises(KeyError, match="sentence"):
        render("basic_given", **frame_values(512, 512))


def test_frame_values_fill_the_last_index_and_pixel():
    assert frame_values(640, 480, 12) == {"width": 640, "height": 480, "max_x": 639, "max_y": 479, "n_images": 12, "last_index": 11}
