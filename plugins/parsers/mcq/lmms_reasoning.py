"""lmms-eval's removal of reasoning blocks, applied to every reply before a task's rule reads it.

lmms-eval (``lmms_eval/api/reasoning.py``, ``strip_reasoning_tags``, with the default
``--reasoning_tags`` of ``__main__.py`` at the pinned commit) strips reasoning in the evaluator,
not in the tasks, so every lmms-eval rule here starts from this one function. Tags match
case-sensitively; an opening tag never closed is left in place.
"""

from __future__ import annotations

#: The default tag pairs of lmms-eval's ``--reasoning_tags``, in the order they are applied.
REASONING_TAGS: tuple[tuple[str, str], ...] = (("<think>", "</think>"), ("<analysis>", "</analysis>"))


def _drop_pair(text: str, opening: str, closing: str) -> str:
    """``text`` with one tag pair's blocks removed, as lmms-eval removes them."""
    while opening in text and closing in text:
        start = text.find(opening)
        end = text.find(closing, start)
        if end == -1:
            # a closing tag only before the first opening tag: no complete block is left
            break
        text = text[:start] + text[end + len(closing) :]
    if closing in text and opening not in text:
        # chat templates that prefill the opening tag leave only its closing tag: the answer
        # is what follows the last one
        text = text.rsplit(closing, 1)[1]
    return text


def strip_reasoning_blocks(text: str) -> str:
    """``text`` without complete reasoning blocks, cut after a dangling closing tag, stripped."""
    for opening, closing in REASONING_TAGS:
        text = _drop_pair(text, opening, closing)
    return text.strip()
