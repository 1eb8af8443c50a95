"""MMSI-Bench's and OmniSpatial's prompt profiles send the text the sets' evaluations send.

The pinned texts were produced by running the upstream functions (a scratch script under /tmp):
lmms-eval @ 75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3 ``lmms_eval/tasks/omnispatial/utils.py``
``omnispatial_doc_to_text`` (its default ``prompt_type: manual_cot``, ``eval_type: re``) on the
question below, and MMSI-Bench @ 5de2f3d2eb0159dbcc76790074029aa400143603
``vlmeval/dataset/mmsi_bench.py`` ``build_prompt``'s text (= lmms-eval ``msr_doc_to_text`` with
the task's default ``post_prompt``).
"""

from __future__ import annotations

import hashlib

from povagent.answers.choice_question import ChoiceQuestion
from povagent.plugins import get_plugin_host
from povagent_plugins.strategies.choice import prompt_profiles
from povagent_plugins.strategies.spatial_set_profiles import mmsi_text, omnispatial_text

OMNI_QUESTION = ChoiceQuestion("From the person's view, which option holds for question 1?", (("A", "1"), ("B", "2"), ("C", "3"), ("D", "4")), "B")
#: sha256 and length of omnispatial_doc_to_text's output on OMNI_QUESTION
OMNI_SHA256 = ("4e3285638ff05b5fc1d2a358219481fae5022d820ec3e2e977b5127972aee545", 1187)
MMSI_QUESTION = ChoiceQuestion("Q?\nOptions: A: x, B: y", (("A", "x"), ("B", "y")), "A")
MMSI_TEXT = "Q?\nOptions: A: x, B: y\nAnswer with the option's letter from the given choices directly. Enclose the option's letter within ``."


def test_omnispatial_is_asked_as_lmms_eval_s_omnispatial_test_asks_it():
    text = omnispatial_text(OMNI_QUESTION)
    assert (hashlib.sha256(text.encode()).hexdigest(), len(text)) == OMNI_SHA256
    assert text.endswith("Answer: X\nwhere X \u2208 {A, B, C, D}.\n\n\nFrom the person's view, which option holds for question 1?\nA. 1\nB. 2\nC. 3\nD. 4")


def test_mmsi_is_asked_as_its_build_prompt_asks_it():
    assert mmsi_text(MMSI_QUESTION) == MMSI_TEXT


def test_both_profiles_are_the_registered_formats():
    profiles = prompt_profiles(get_plugin_host())
    assert profiles["mmsi"].text is mmsi_text and profiles["omnispatial"].text is omnispatial_text
