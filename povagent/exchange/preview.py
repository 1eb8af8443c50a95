"""What the model sees: a request rendered as text, with its images saved beside it.

Behind ``povagent show-prompt``: images appear as one line each naming their label, full
content hash and size (and whether markers were drawn on them), text parts verbatim, in message
order, followed by the generation parameters and the answer schema. Nothing here calls a model.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Request, TextPart
from povagent.files.confined_write import write_inside


@dataclass
class SavedImage:
    """An image of the request written to disk; ``marked`` when it differs from the source frame."""

    position: int
    label: str
    image_hash: str
    path: Path | None
    marked: bool


@dataclass
class PromptPreview:
    """The rendered text of a request and the images it shows."""

    text: str
    images: list[SavedImage] = field(default_factory=list)


def _slug(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "-", label).strip("-").lower() or "image"


def preview_request(
    request: Request, images: ImageStore, instance: Instance | None = None, out_dir: Path | None = None
) -> PromptPreview:
    """Render ``request`` as text; with ``out_dir``, save every image it shows there as PNG.

    With ``instance`` an image whose hash is not one of the instance's frame files is reported
    as ``marked`` (a derived image: markers drawn on it).
    """
    sources = {images.add_file(f.file).image_hash for f in instance.frames} if instance is not None else set()
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
    lines: list[str] = []
    saved: list[SavedImage] = []
    for m_index, message in enumerate(request.messages, start=1):
        lines.append(f"--- message {m_index} ({message.role}) ---")
        for part in message.parts:
            if isinstance(part, TextPart):
                lines.append(part.text)
                continue
            assert isinstance(part, ImagePart)
            info = images.info(part.image_hash)
            marked = instance is not None and part.image_hash not in sources
            path = None
            if out_dir is not None:
                suffix = "marked" if marked else "frame"
                path = out_dir / f"{len(saved):02d}_{_slug(part.label)}_{suffix}_{part.image_hash[:12]}.png"
                # aside and renamed: a link left under the name in a reused folder is replaced
                write_inside(out_dir, path.name, images.encoded_bytes(part.image_hash))
            saved.append(SavedImage(len(saved), part.label, part.image_hash, path, marked))
            note = " marked" if marked else ""
            where = f" -> {path}" if path is not None else ""
            lines.append(f"[image{note}: {part.label or 'unlabelled'} sha256:{part.image_hash} {info.width}x{info.height}{where}]")
        lines += [f"[tool call {c.id}: {c.name}({c.arguments})]" for c in message.tool_calls]
    if request.tools:  # the functions offered, as sent (litellm's tools=)
        lines.append(f"--- tools: {json.dumps([dict(t) for t in request.tools], sort_keys=True, indent=1)}")
    lines.append(f"--- generation: {json.dumps(request.generation.as_dict(), sort_keys=True)}")
    lines.append(f"--- answer schema: {json.dumps(request.answer.json_schema, sort_keys=True)}")
    return PromptPreview("\n".join(lines), saved)
