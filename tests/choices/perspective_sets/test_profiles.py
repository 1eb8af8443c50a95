"""Each set is asked in its own published wording, its images where the set puts them."""

from __future__ import annotations

from povagent.dataset.choice_sets import load_choice_set
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart
from povagent_plugins.strategies.choice import ChoiceStrategy


def _parts(set_file, format, index=0, **options):
    instance = load_choice_set(set_file(format), format).instances()[index]
    request = ChoiceStrategy(**options).build(instance, ImageStore())
    (message,) = request.messages
    return [("image", p.label) if isinstance(p, ImagePart) else ("text", p.text) for p in message.parts]


def test_viewspatial_is_asked_with_its_papers_question_choices_answer_lines(set_file):
    assert _parts(set_file, "viewspatial", 1) == [
        ("image", "Image 0"), ("image", "Image 1"),
        ("text", "Question: Standing at the fridge facing the table, where is the window?\n"
                 "Choices: A. front\nB. back\nC. left\nD. right\nReply only to the corresponding option.\nAnswer:"),
    ]  # fmt: skip


def test_mindcube_puts_each_image_at_its_marker_after_the_raw_qa_instruction(set_file):
    parts = _parts(set_file, "mindcube", 2)
    assert [kind for kind, _ in parts] == ["text", "image", "text", "image", "text", "image", "text"]
    assert parts[0][1].startswith("[Task]\nYour task is to analyze the spatial arrangement") and parts[0][1].endswith("[Question]")
    assert parts[2:] == [("text", "The first view."), ("image", "Image 1"), ("text", "The second view."), ("image", "Image 2"),
                         ("text", "The third view. Which way did the camera turn between the first and the third view? A. Left B. Right")]  # fmt: skip


def test_3dsrbench_is_asked_with_its_options_block_and_its_instruction(set_file):
    assert _parts(set_file, "3dsrbench", 0) == [
        ("image", "Image 0"),
        ("text", "Question: Is the man on the left of the car, from the car's view?\nOptions:\nA. yes\nB. no\n"
                 "Please select the correct answer from the options above. \n"),
    ]  # fmt: skip


def test_the_profile_option_overrides_a_sets_wording_and_plain_keeps_the_images_first(set_file):
    parts = _parts(set_file, "mindcube", 1, profile="plain")
    assert [kind for kind, _ in parts] == ["image", "text"]
    assert parts[1][1].endswith("Answer with the option's letter from the given choices directly.")
