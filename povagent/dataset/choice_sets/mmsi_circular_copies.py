"""MMSI-Bench's circular split: each question of ``MMSI_Bench.parquet`` asked four times, its
options rotated, as the set's authors build ``MMSI_Bench_Circular``.

The authors' ``MMSIBenchCircular.load_data`` (``vlmeval/dataset/mmsi_bench.py`` in their
VLMEvalKit fork, InternRobotics/MMSI-Bench@5de2f3d2eb0159dbcc76790074029aa400143603) reads each
question's options again from its text, and this module reads them as it does:

- the question is split at its *first* ``Options:``; the text before it, stripped, is the
  question proper;
- in the text after it (stripped), each label ``A``-``D`` followed by a colon (spaces allowed
  around it) starts an option, which runs, as short as it can, up to the next such label after
  a space or a comma, or to the end of the line; its text is stripped. A label met twice keeps
  its first place and its last text. ``E`` and later labels are not labels there (an ``E: ...``
  stays inside ``D``'s text);
- a question with no such option, or whose gold letter names none of them, is left out (the
  authors' code skips it with a printed line; here it is a problem naming the record).

Copy ``k`` (0 to 3) takes the options in the order ``ABCD``, ``BCDA``, ``CDAB``, ``DABC``: label
``ABCD[j]`` shows the option first labelled ``order[j]``, a label whose option the question lacks
left out (so a three-option question's rotations may skip a letter, as there), and the gold is
the label the gold option now carries. The question is written again as the question proper, a
line break, and ``Options: A: ..., B: ...`` (comma-separated), which the set's prompt then asks.
Copy ``k`` of the question with id ``i`` has the id ``i + k * 1,000,000`` (the authors' index,
and VLMEvalKit's for every circular set), so an id must be a whole number below 1,000,000; its
:class:`~povagent.answers.choice_question.ChoiceQuestion` records the question (``group``: ``i``) and the
order (``variant``). Every copy shows the question's images.

This module only builds the copies from the items :func:`~.mmsi.read_mmsi` reads; scoring them
(a question right only when all its copies are) is the ``choice-mmsi-circular`` scorer's.
"""

from __future__ import annotations

import re
from pathlib import Path

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.external import Item
from povagent.dataset.choice_sets.mmsi_records import PROFILE, read_mmsi
from povagent.dataset.problems import Problem

#: The option orders of the four copies, the first the question as written.
ROTATIONS = ("ABCD", "BCDA", "CDAB", "DABC")
#: How far apart the ids of a question's copies are (the authors' ``index + k * 1e6``).
COPY_STRIDE = 1_000_000
_OPTIONS_MARK = "Options:"
#: One option as the authors' code reads it: a label A-D, its colon, then the text, as short as
#: it can be, up to the next label after whitespace or a comma, or the end of the line.
_OPTION = re.compile(
    r"""([A-D]) \s* : \s*
        (.*?)
        (?= \s+ [A-D] \s* : | , \s* [A-D] \s* : | $ )""",
    re.VERBOSE,
)


def split_options(question: str) -> tuple[str, dict[str, str]]:
    """The question proper and its options ``{label: text}`` as the authors' circular split reads
    them (module docstring); ``(question stripped, {})`` when it has no ``Options:``."""
    head, mark, tail = question.partition(_OPTIONS_MARK)
    if not mark:
        return question.strip(), {}
    options: dict[str, str] = {}
    for label, text in _OPTION.findall(tail.strip()):
        options[label] = text.strip()
    return head.strip(), options


def rotated_copies(item: Item) -> list[Item] | str:
    """The four copies of ``item`` (module docstring), or why it has none."""
    base = item.id
    if not base.isascii() or not base.isdigit() or int(base) >= COPY_STRIDE:
        return f"{base!r} is not a whole number below {COPY_STRIDE:,}, and the circular split numbers a question's copies id + k * {COPY_STRIDE:,}"
    question, options = split_options(item.question.question)
    gold = item.question.gold
    if gold not in options:
        found = ", ".join(options) or "none"
        return f"the gold letter {gold!r} names none of the options A-D the circular split reads in it ({found}); question left out, as the set's code skips it"
    copies = []
    for k, order in enumerate(ROTATIONS):
        shown = tuple((label, options[was]) for label, was in zip("ABCD", order) if was in options)
        listed = ", ".join(f"{label}: {text}" for label, text in shown)
        asked = ChoiceQuestion(
            f"{question}\n{_OPTIONS_MARK} {listed}",
            shown,
            "ABCD"[order.index(gold)],
            category=item.question.category,
            group=str(int(base)),
            variant=order,
            profile=PROFILE,
        )
        copies.append(Item(str(int(base) + k * COPY_STRIDE), asked, item.images, embedded=item.embedded))
    return copies


def read_mmsi_circular(file: Path, cache: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound row of ``MMSI_Bench.parquet`` (:func:`~.mmsi.read_mmsi`) as its four rotated
    copies, a question's copies together; one problem per row left out."""
    items, problems = read_mmsi(file, cache)
    copies: list[Item] = []
    seen: set[str] = set()
    for item in items:
        made = rotated_copies(item)
        if isinstance(made, str):
            problems.append(Problem(str(file), f"record {item.id}.question" if "gold" in made else f"record {item.id}.id", made))
        elif made[0].id in seen:  # "7" and "007" are one question number
            problems.append(Problem(str(file), f"record {item.id}.id", f"names question {made[0].id}, as an earlier row does; this one left out"))
        else:
            seen.add(made[0].id)
            copies.extend(made)
    return copies, problems


__all__ = ["COPY_STRIDE", "ROTATIONS", "read_mmsi_circular", "rotated_copies", "split_options"]
