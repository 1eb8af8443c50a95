"""Which loader reads a dataset folder: the one choice every command makes the same way.

A folder holding ``realworld.json`` is a real-world set (:mod:`povagent.dataset.realworld`);
any other folder, a POVBench release or a generated set (written in the release layout), is
read by the release loader (:mod:`povagent.dataset.loader`). A ``format`` names an external
multiple-choice set's file (``viewspatial``, ``mindcube``, ``3dsrbench``), read by its reader
(:mod:`povagent.dataset.choice_sets`). ``run``, ``rescore``,
``show-prompt`` and the report all open a set through :func:`open_evaluation_set`, so a set
one of them reads is never one another refuses ("no house folders ... is this a POVBench
dataset?" for the shipped real-world demo). This module must not generate or fetch a set
(see :func:`povagent.run.pending.prepare_dataset`).
"""

from __future__ import annotations

from pathlib import Path

from povagent.dataset.protocol import EvaluationSet


def open_evaluation_set(
    root: str | Path, *, strict: bool = False, check_images: bool = True, format: str | None = None, images: str | Path | None = None
) -> EvaluationSet:
    """The set at ``root``, read by the loader its kind needs.

    ``strict`` and ``check_images`` are the release loader's (a real-world set is checked
    whole as it is read, and its frames are read to letterbox them; an external set's images
    are checked as it is read). ``format`` (``dataset.format``) makes ``root`` an external
    set's file, read in that format, its image paths relative to ``images`` (default: the
    file's folder).
    """
    if format is not None:
        from povagent.dataset.choice_sets import load_choice_set

        return load_choice_set(root, format, images=images)
    from povagent.dataset.realworld import is_realworld, load_realworld

    if is_realworld(root):
        return load_realworld(root)
    from povagent.dataset.loader import load_dataset

    return load_dataset(root, strict=strict, check_images=check_images)
