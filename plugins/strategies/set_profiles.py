"""The perspective-taking sets' own prompt wordings, as their evaluations send them.

Each function is the text one set's evaluation puts around a question, re-written here from the
code named in its source (lmms-eval @ 75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3; MindCube @
6d8fd9acdf5b80769373a21cdbfcf068ab356e0f). The images come first (ViewSpatial-Bench,
3DSRBench) or at each ``<image>`` marker of the question (MindCube): the ``choice`` strategy
places them (each set's format plugin, ``povagent_plugins.formats``, names its profile and
whether it interleaves). Pure text: nothing here reads files.
"""

from __future__ import annotations

from povagent.answers.choice_question import ChoiceQuestion

VIEWSPATIAL_SOURCE = "lmms-eval viewspatial_doc_to_text (the ViewSpatial-Bench paper's format), lmms-eval @ 75571cfe"
MINDCUBE_SOURCE = (
    "MindCube raw_qa template (src/prompt_generation/templates.py @ 6d8fd9ac); images at its <image> markers as lmms-eval mindcube_doc_to_messages places them"
)
SRBENCH3D_SOURCE = "lmms-eval 3dsrbench doc_to_text (VLMEvalKit's layout, no hint), lmms-eval @ 75571cfe"

#: MindCube's raw-QA instruction, sent before the question.
MINDCUBE_INSTRUCTION = (
    "[Task]\n"
    "Your task is to analyze the spatial arrangement of objects in the scene by examining the provided images, "
    "which show the scene from different viewpoints.\n"
    "[Answer Instruction]\n"
    "You only need to provide *ONE* correct answer selecting from the options listed below. For example, if you "
    "think the correct answer is 'A. Above' from 'A. Above B. Under C. Front D. Behind', your response should "
    "**only** be '<answer>A. Above</answer>'.\n"
)


def viewspatial_text(question: ChoiceQuestion) -> str:
    """``Question: ...``, ``Choices: `` and the options one a line, then the reply instruction."""
    return f"Question: {question.question}\nChoices: {question.options_block()}\nReply only to the corresponding option.\nAnswer:"


def mindcube_text(question: ChoiceQuestion) -> str:
    """The raw-QA instruction, then ``[Question]`` and the question as the set writes it (its
    ``<image>`` markers and inline options kept: the strategy puts the images at the markers)."""
    return f"{MINDCUBE_INSTRUCTION}\n[Question]\n{question.question}"


def srbench3d_text(question: ChoiceQuestion) -> str:
    """``Question: ...``, ``Options:`` one a line, then the instruction to select one."""
    options = "".join(f"{label}. {text}\n" for label, text in question.options)
    return f"Question: {question.question}\nOptions:\n{options}Please select the correct answer from the options above. \n"
