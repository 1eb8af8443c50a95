"""Prompt templates: loading the files of ``povagent_prompts`` and filling their placeholders.

Templates use :class:`string.Template` syntax (``$name``) and are read through
:mod:`importlib.resources`, so they work from a wheel as from the source tree. Filling is strict
(``substitute``): a placeholder without a value is an error, never silent text like ``$width``.
This module knows nothing about strategies or message layout; see ``prompts/README.md`` for the
templates (the authors' runner's texts, and the paper appendix's as the ``appendix_*`` variant)
and their placeholders.
"""

from __future__ import annotations

from functools import cache, lru_cache
from importlib.resources import files
from string import Template
from typing import Any

#: The package holding the template files.
TEMPLATE_PACKAGE = "povagent_prompts"


@cache
def load_template(name: str) -> str:
    """The text of template ``name`` (``"basic_frames"`` or ``"basic_frames.txt"``).

    The file's final newline is dropped: it is a file convention, not part of the prompt.
    Raises ``FileNotFoundError`` naming the template when it does not exist.
    """
    filename = name if name.endswith(".txt") else f"{name}.txt"
    resource = files(TEMPLATE_PACKAGE).joinpath(filename)
    if not resource.is_file():
        raise FileNotFoundError(f"no prompt template {filename!r} in {TEMPLATE_PACKAGE}")
    text = resource.read_text(encoding="utf-8")
    return text[:-1] if text.endswith("\n") else text


def render(name: str, **values: Any) -> str:
    """Template ``name`` with every ``$placeholder`` filled from ``values`` (all required)."""
    return Template(load_template(name)).substitute({k: str(v) for k, v in values.items()})


def coordinate_system(width: int, height: int) -> str:
    """The coordinate-system paragraph of the pixel prompts, filled for a ``width`` x ``height`` frame."""
    return _coordinate_system(int(width), int(height))


@lru_cache(maxsize=64)
def _coordinate_system(width: int, height: int) -> str:
    return render("coordinate_system", width=width, height=height, max_x=width - 1, max_y=height - 1)


def frame_values(width: int, height: int, n_images: int | None = None) -> dict[str, Any]:
    """The size placeholders of a prompt: ``width``, ``height``, ``max_x``, ``max_y``, the filled
    ``coordinate_system`` paragraph and, for a multi-frame prompt, ``n_images`` and ``last_index``."""
    values: dict[str, Any] = {
        "width": width,
        "height": height,
        "max_x": width - 1,
        "max_y": height - 1,
        "coordinate_system": coordinate_system(width, height),
    }
    if n_images is not None:
        values.update(n_images=n_images, last_index=n_images - 1)
    return values
