"""The ``grid`` strategy: the basic prompt over frames carrying a labelled pixel grid.

An example of a complete third-party povagent plugin (see this package's README). The grid
gives the model a ruler: lines every ``spacing`` pixels, each labelled with its coordinate,
so the answer's pixel coordinates can be read off the image. The prompt is the paper's basic
prompt plus one sentence that describes the grid; the answer format is unchanged, so any
povagent parser reads the answers.
"""

from __future__ import annotations

import json
from typing import Any

from PIL import Image, ImageColor, ImageDraw

from povagent import hookimpl
from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, Request
from povagent.exchange.prompts import frame_values, render
from povagent.interfaces import Strategy
from povagent_plugins.strategies.layout import answer_spec, prompt_message

__version__ = "0.1.0"

GRID_NOTE = (
    "Each image carries a thin {color} grid: lines every {spacing} pixels, labelled with their pixel "
    "coordinate (x along the top edge, y along the left edge). Use it to read off coordinates."
)


def draw_grid(image: Image.Image, spacing: int, color: tuple[int, int, int], line_width: int, labels: bool) -> Image.Image:
    """A copy of ``image`` with grid lines every ``spacing`` pixels (and coordinate labels)."""
    out = image.convert("RGB").copy()
    draw = ImageDraw.Draw(out)
    width, height = out.size
    for x in range(spacing, width, spacing):
        draw.line([(x, 0), (x, height - 1)], fill=color, width=line_width)
        if labels:
            draw.text((x + 2, 1), str(x), fill=color)
    for y in range(spacing, height, spacing):
        draw.line([(0, y), (width - 1, y)], fill=color, width=line_width)
        if labels:
            draw.text((2, y + 1), str(y), fill=color)
    return out


class GridStrategy(Strategy):
    """The basic prompt; every frame shown with a labelled pixel grid."""

    def __init__(
        self,
        spacing: int = 64,
        color: str = "yellow",
        line_width: int = 1,
        labels: bool = True,
        max_tokens: int = 256,
        temperature: float | None = None,
    ) -> None:
        if not isinstance(spacing, int) or isinstance(spacing, bool) or not 8 <= spacing <= 512:
            raise ValueError(f"strategy option spacing must be an integer number of pixels in [8, 512], got {spacing!r}")
        try:
            rgb = ImageColor.getrgb(color)
        except (ValueError, AttributeError):
            raise ValueError(f"strategy option color: unknown colour {color!r}") from None
        if not isinstance(line_width, int) or isinstance(line_width, bool) or line_width < 1:
            raise ValueError(f"strategy option line_width must be a positive integer, got {line_width!r}")
        if not isinstance(max_tokens, int) or isinstance(max_tokens, bool) or max_tokens < 1:
            raise ValueError(f"strategy option max_tokens must be a positive integer, got {max_tokens!r}")
        self.spacing = spacing
        self.color_name = color
        self.color = (int(rgb[0]), int(rgb[1]), int(rgb[2]))
        self.line_width = line_width
        self.labels = bool(labels)
        self.generation = GenerationParams(max_tokens=max_tokens, temperature=temperature)

    def recipe_key(self) -> str:
        """Everything that changes the drawing (the image store makes each derived frame once)."""
        return json.dumps(
            {"plugin": "grid", "version": __version__, "spacing": self.spacing, "color": self.color,
             "line_width": self.line_width, "labels": self.labels},
            sort_keys=True,
        )

    def images_for(self, instance: Instance, images: ImageStore) -> list[str]:
        """Hashes of the gridded frames, in order."""
        key = self.recipe_key()
        hashes = []
        for frame in instance.frames:
            source = images.add_file(frame.file).image_hash
            gridded = images.derive(
                source, key, lambda im: draw_grid(im, self.spacing, self.color, self.line_width, self.labels)
            )
            hashes.append(gridded.image_hash)
        return hashes

    def prompt_text(self, instance: Instance) -> str:
        """The basic prompt with the grid note before its closing instructions."""
        width, height = instance.frame_size
        if instance.condition.uses_exploration_frames:
            text = render("basic_frames", sentence=instance.sentence, **frame_values(width, height, len(instance.frames)))
        else:
            text = render("basic_given", sentence=instance.sentence, **frame_values(width, height))
        note = GRID_NOTE.format(color=self.color_name, spacing=self.spacing)
        marker = "IMPORTANT:"
        if marker in text:
            head, tail = text.split(marker, 1)
            return f"{head}{note}\n{marker}{tail}"
        return f"{text}\n{note}"

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """One user message: gridded frames (labelled "Image i:"), then the prompt."""
        message = prompt_message(instance, self.images_for(instance, images), self.prompt_text(instance))
        return Request(messages=(message,), answer=answer_spec(instance), generation=self.generation, instance=instance)


@hookimpl
def register_strategies(register: Any) -> None:
    """Contribute the grid strategy."""
    register("grid", GridStrategy, description="Basic prompt over frames with a labelled pixel grid (example plugin)")
