"""MMSI-Bench's and OmniSpatial's own prompt wordings, as their evaluations send them.

Re-written from the code named in each source (MMSI-Bench @ 5de2f3d2; lmms-eval @ 75571cfe). The
images come first in both; the ``choice`` strategy places them. Pure text: nothing here reads
files.

OmniSpatial's evaluation asks for the reply format its rule reads; its default, sent here, is the
manual chain-of-thought instruction, then "end with ``Answer: X``" (read by ``omnispatial-re``).
The set's ``api_eval.py`` sends the instruction as a system message; lmms-eval's
``omnispatial_test`` task sends it at the head of the one user message, as this profile does.
"""

from __future__ import annotations

from povagent.answers.choice_question import ChoiceQuestion

MMSI_SOURCE = "MMSI-Bench's build_prompt (vlmeval/dataset/mmsi_bench.py @ 5de2f3d2) = lmms-eval mmsi_bench's default post_prompt @ 75571cfe"
OMNISPATIAL_SOURCE = "lmms-eval omnispatial_doc_to_text, prompt_type manual_cot (OmniSpatial api_eval.py's default), lmms-eval @ 75571cfe"

#: MMSI-Bench's instruction after the question (its options are inside the question).
MMSI_POST_PROMPT = "Answer with the option's letter from the given choices directly. Enclose the option's letter within ``."

#: OmniSpatial's manual chain-of-thought instruction (``prompt_type manual_cot``, its default).
OMNISPATIAL_INSTRUCTION = (
    "\nYou are a spatial-reasoning assistant.\n\nTask\n-----\nYou will receive\n"
    "1. **Image** - a single RGB frame depicting a scene.\n"
    "2. **Question** - a natural-language query about spatial relationships between objects in the image.\n"
    "3. **Options** - \u22652 answer candidates, each tagged by a capital letter (A, B, C, D\u2026).\n\n"
    "Guidelines\n----------\nPlease follow these steps to analyze the image and answer the question:\n"
    "1. First, carefully observe the image and identify all relevant objects and their spatial relationships.\n"
    "2. Next, break down the question into key components that need to be addressed.\n"
    "3. Think through the spatial reasoning step-by-step to arrive at your answer. "
    "It may be necessary to transfer perspective to better understand the scene.\n"
    "4. Finally, select the most appropriate option (A, B, C, or D) based on your analysis.\n\n"
    "Always ground your answer in the visual evidence; do not hallucinate unseen objects.\n"
    "If uncertain, pick the most plausible option\u2014never refuse or reply \u201cinsufficient information.\u201d\n"
)
#: The reply format OmniSpatial's default ``re`` rule reads, as its prompt asks for it (``RE_FORMAT``).
OMNISPATIAL_RE_FORMAT = "\nEnd your answer with a separate line formatted exactly as:\n\nAnswer: X\nwhere X \u2208 {A, B, C, D}.\n"


def mmsi_text(question: ChoiceQuestion) -> str:
    """The question as the set writes it (options inside), then the instruction to answer in backticks."""
    return f"{question.question}\n{MMSI_POST_PROMPT}"


def omnispatial_text(question: ChoiceQuestion) -> str:
    """The instruction and the reply format, a blank line, the question, then ``A. text`` a line."""
    options = "".join(f"\n{label}. {text}" for label, text in question.options)
    return f"{OMNISPATIAL_INSTRUCTION}\n{OMNISPATIAL_RE_FORMAT}\n\n{question.question}{options}"
