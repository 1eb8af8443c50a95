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
    """``text`` with one tag pair's blocks removed, as lmms-eval removes them.

    lmms-eval removes the block from the first opening tag to the first closing tag after it,
    then looks again from the start, until no opening tag has a closing tag after it. Copying
    the whole text at each removal would take quadratic time on a reply of many blocks, so the
    text already kept is never searched again: no opening tag can start in it, except one
    completed by the text a removal brings next to it, which can only start among its last
    ``len(opening) - 1`` characters (``head``).
    """
    kept: list[str] = []  # the result before ``head``
    head = ""  # the last kept characters, where an opening tag may start across a removal
    pos = 0  # the rest of the result is text[pos:]
    while True:
        joined = head + text[pos : pos + len(opening)]
        at = joined.find(opening)
        start = pos + at - len(head) if 0 <= at < len(head) else text.find(opening, pos)
        if start == -1 or (end := text.find(closing, max(pos, start + len(opening)))) == -1:
            break
        before = head + text[pos:start] if start >= pos else head[: len(head) - (pos - start)]
        keep = len(opening) - 1
        kept.append(before[: len(before) - keep] if len(before) > keep else "")
        head = before[-keep:] if len(before) > keep else before
        pos = end + len(closing)
    result = "".join(kept) + head + text[pos:]
    if closing in result and opening not in result:
        # chat templates that prefill the opening tag leave only its closing tag: the answer
        # is what follows the last one
        result = result.rsplit(closing, 1)[1]
    return result


def strip_reasoning_blocks(text: str) -> str:
    """``text`` without complete reasoning blocks, cut after a dangling closing tag, stripped."""
    for opening, closing in REASONING_TAGS:
        text = _drop_pair(text, opening, closing)
    return text.strip()
