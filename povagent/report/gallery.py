"""The gallery: each prediction drawn on the frame it was scored in, saved as small JPEGs.

For every shown row: the frame the model selected (A/B) or the observer view (C), with the GT
point (green ring) and the predicted point (red cross) drawn on it. A GT behind the camera is
drawn as a dashed ring at the image centre (where the official metric puts it); a GT in front of
the camera but outside the frame as an arrow at the border. Two files per drawing: a 256 px
thumbnail for the grid and the full-size frame for the viewer.

Files are named by a SHA-256 of what was drawn (the source image's bytes plus the markers), so
the HTML references images by hash, a re-run finds its images already made and skips them,
and two rows with the same drawing share one file. Nothing is inlined as base64.

An Inferred or Stated card also gets a strip of the house's exploration frames (the frames the
model was shown, in order), with the selected one outlined and the frames that could show the
target ticked. One small JPEG per house holds every frame side by side (``images/<sha256>.s.jpg``,
about 1 kB a frame), shared by all of that house's cards; the page crops it per tile. "Could
show the target" (:func:`ground_truth_views`) starts from the official metric's own test, the GT
3D point projecting in front of the frame's camera and inside its bounds; that test sees through
walls, so the exploration log's record of the objects seen in each frame
(``object_in_frame_hits``, occlusion-aware) splits it: the anchor the target is placed beside
was seen (ticked), or not (marked "maybe hidden"). The release records objects, never the
target point itself, so the anchor is the nearest record there is. A real-world set's hand
marks say it directly: a frame is ticked when it carries a mark.

Raw answers (a chain-of-thought answer runs to thousands of characters) are kept out of the
page too: :func:`write_answer_chunks` moves them into small ``answers/<sha256>.js`` files that
the page loads with a ``<script>`` tag (which works from ``file://``, unlike ``fetch``) only
when a card is opened, so the page stays small whatever the models wrote. The transcript goes
there as well: every turn of the row, the request as sent (images named by their labels) and
the model's raw answer (``tr``; ``nt`` on the page counts the turns).

A source image that cannot be read or decoded (truncated, corrupt, not an image) never stops
the report: its card says "image not drawn" with the file and the reason (``ie`` in the entry),
and every other card is drawn as usual.

This module draws and writes images only; it never scores (markers use the stored scores where
they exist: the official projection, or the success scorer's hit radius).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from PIL import Image

from povagent.dataset.realworld_set import RealWorldInstance
from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular
from povagent.files.confined_write import write_inside
from povagent.report.active_section import answered_view
from povagent.report.birds_eye import birds_eye_for_row
from povagent.report.collect import MAX_RAW_CHARS, Observation, row_turns
from povagent.report.gallery_choice import asked_question, asks_numeric_question, choice_fields, has_target, question_drawing, shows_several_images
from povagent.report.gallery_drawing import IMAGE_ERRORS, Drawing, image_error, open_frame, render
from povagent.report.html import script_json
from povagent.report.run_sets import RunSets
from povagent.scoring.normalized_l2 import project_ground_truth, scoring_frame

IMAGES_DIR = "images"
ANSWERS_DIR = "answers"
#: Entries per answers file: one file is loaded when any of its cards is opened.
ANSWER_CHUNK = 200
THUMB_SIZE = 256

#: Height of one frame in a strip image (the page shows it at 18 to 64 px).
STRIP_TILE_HEIGHT = 64



@dataclass
class GalleryStats:
    """How the gallery images were obtained."""

    entries: int = 0
    drawn: int = 0
    cached: int = 0
    without_image: int = 0
    #: Drawings whose source image could not be read or decoded (their cards say so).
    bad_images: int = 0
    seconds: float = 0.0
    #: Frame strips, one per house shown: ``{"k": key, "n": frames, "w": tile w, "h": tile h}``;
    #: an entry's ``fs`` is an index into this list.
    strips: list[dict[str, Any]] = field(default_factory=list)
    #: Each distinct ``[seen, maybe hidden]`` pair of frame lists (:func:`ground_truth_views`);
    #: an entry's ``fw`` is an index into it. Every system's card of an instance, and the
    #: Inferred and Stated cards of one target, share one pair: the page stays small.
    views: list[list[list[int]]] = field(default_factory=list)


@dataclass
class _SourceHashes:
    """SHA-256 of each source frame, computed once per file."""

    known: dict[Path, str] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def of(self, path: Path) -> str:
        with self.lock:
            h = self.known.get(path)
        if h is None:
            h = hashlib.sha256(read_regular(path, MAX_IMAGE_FILE_BYTES, what="image")).hexdigest()
            with self.lock:
                self.known[path] = h
        return h


def drawing_for(observation: Observation, instance: Any, frame: Any | None = None) -> Drawing | None:
    """The drawing of one row, or ``None`` when no frame was selected (or it is unknown);
    ``frame`` is the image answered in when it is no dataset frame (an active-mode view)."""
    frame = frame if frame is not None else scoring_frame(instance, observation.selected_image, observation.image_path)
    if frame is None:
        return None
    if isinstance(instance, RealWorldInstance):
        return _marked_drawing(observation, instance, frame)
    cam = frame.camera
    w, h = cam.width, cam.height
    gt = project_ground_truth(instance.target, cam)
    if gt.behind:
        gt_px, state = (w / 2.0, h / 2.0), "behind"
    else:
        gt_px, state = (gt.u * w, gt.v * h), ("in" if gt.in_frame else "out")
    pred = (observation.x, observation.y) if observation.x is not None and observation.y is not None else None
    return Drawing(Path(frame.file), gt_px, state, pred)


def ground_truth_views(instance: Any) -> tuple[list[int], list[int]]:
    """The exploration frames (indices) that could show an instance's target: ``(seen, maybe_hidden)``.

    POVBench-format: a frame qualifies when the GT 3D point projects in front of its camera and
    inside its bounds (:func:`povagent.scoring.normalized_l2.project_ground_truth`, the test behind
    the metric's "GT in the selected frame", which ignores walls). It is *seen* when the
    exploration log also records the anchor object in that frame (or records no object at all,
    so cannot tell), *maybe hidden* when the log lists what the frame saw and the anchor is
    not among it. A real-world set: the frames that carry a hand-made mark, all seen.
    """
    if isinstance(instance, RealWorldInstance):
        return [f.index for f in instance.frames if instance.marks_in(f.image_path)], []
    anchor = instance.anchor_object.objectId
    seen: list[int] = []
    hidden: list[int] = []
    for i, f in enumerate(instance.frames):
        if project_ground_truth(instance.target, f.camera).in_frame:
            (seen if not f.in_frame_hits or anchor in f.in_frame_hits else hidden).append(i)
    return seen, hidden


@dataclass(frozen=True)
class Strip:
    """A house's exploration frames as one row of tiles (the card's frame strip)."""

    sources: tuple[Path, ...]
    tile: tuple[int, int]

    def key(self, hashes: _SourceHashes) -> str:
        """The SHA-256 naming the strip's file (every frame's bytes, in order, and the tile size)."""
        payload = "strip:" + json.dumps([self.tile, [hashes.of(p) for p in self.sources]])
        return hashlib.sha256(payload.encode()).hexdigest()


def strip_file(images_dir: Path, key: str) -> Path:
    """Where a strip image is written."""
    return images_dir / f"{key}.s.jpg"


def write_strip(strip: Strip, images_dir: Path, key: str) -> bool:
    """Draw the strip's image unless it exists; True if drawn now (IMAGE_ERRORS if a frame is bad)."""
    path = strip_file(images_dir, key)
    if path.exists():
        return False
    tw, th = strip.tile
    sheet = Image.new("RGB", (tw * len(strip.sources), th), (34, 34, 34))
    for i, source in enumerate(strip.sources):
        with open_frame(source) as src:
            src.draft("RGB", (tw, th))  # JPEG sources decode at a fraction of their size
            sheet.paste(src.convert("RGB").resize((tw, th), Image.Resampling.BILINEAR), (i * tw, 0))
    _save_jpeg(sheet, path, 72)
    return True


def _save_jpeg(image: Image.Image, path: Path, quality: int) -> None:
    # Encoded in memory, then written aside and renamed: a link planted at the name (the report
    # folder may lie in an untrusted run folder) is replaced, never followed.
    buffer = io.BytesIO()
    image.save(buffer, "JPEG", quality=quality)
    write_inside(path.parent, path.name, buffer.getvalue(), unique=True)  # drawn by several threads


def _strip_of(instance: Any) -> Strip | None:
    """The strip of an instance's exploration frames, or of a multiple-choice question's
    images when it has several (``None`` for Given, or a single image, or no frames)."""
    if not (getattr(instance.condition, "uses_exploration_frames", False) or shows_several_images(instance)) or not instance.frames:
        return None
    w, h = instance.frame_size
    return Strip(tuple(Path(f.file) for f in instance.frames), (max(1, round(STRIP_TILE_HEIGHT * w / h)), STRIP_TILE_HEIGHT))


@dataclass
class _StripBook:
    """The strips and GT-view lists of one gallery, each worked out once per instance (a sweep
    shows every instance once per cell) and stored once (``stats.strips``, ``stats.views``)."""

    stats: GalleryStats
    hashes: _SourceHashes
    jobs: dict[str, Strip] = field(default_factory=dict)
    by_strip: dict[Strip, int] = field(default_factory=dict)
    by_views: dict[str, int] = field(default_factory=dict)
    by_instance: dict[str, dict[str, Any]] = field(default_factory=dict)

    def fields(self, instance_id: str, instance: Any) -> dict[str, Any]:
        """An entry's ``{"fs": strip, "fw": views}`` (``{}``: no strip for this card)."""
        known = self.by_instance.get(instance_id)
        if known is None:
            known = self.by_instance[instance_id] = self._work_out(instance)
        return known

    def _work_out(self, instance: Any) -> dict[str, Any]:
        strip = _strip_of(instance)
        if strip is None or not all(p.exists() for p in strip.sources):
            return {}
        if strip not in self.by_strip:
            try:
                key = strip.key(self.hashes)
            except (OSError, ReadTargetError):
                return {}  # a frame cannot be read (or is a pipe): no strip (the card says why its image is missing)
            self.by_strip[strip] = len(self.stats.strips)
            self.stats.strips.append({"k": key, "n": len(strip.sources), "w": strip.tile[0], "h": strip.tile[1]})
            self.jobs[key] = strip
        views = list(ground_truth_views(instance)) if has_target(instance) else [[], []]  # no 3D target: no tick
        index = self.by_views.setdefault(json.dumps(views), len(self.stats.views))
        if index == len(self.stats.views):
            self.stats.views.append(views)
        return {"fs": self.by_strip[strip], "fw": index}

    def views_fields(self, active: Any) -> dict[str, Any]:
        """An active row's ``{"vs": strip, "va": view answered in}``: the views its episode
        rendered, as one more strip (``{}``: none rendered, or one cannot be read)."""
        if active is None or not active.views or not all(p.exists() for p in active.views):
            return {}
        with open_frame(active.views[0]) as first:
            w, h = first.size
        strip = Strip(active.views, (max(1, round(STRIP_TILE_HEIGHT * w / h)), STRIP_TILE_HEIGHT))
        if strip not in self.by_strip:
            try:
                key = strip.key(self.hashes)
            except (OSError, ReadTargetError):
                return {}
            self.by_strip[strip] = len(self.stats.strips)
            self.stats.strips.append({"k": key, "n": len(strip.sources), "w": strip.tile[0], "h": strip.tile[1]})
            self.jobs[key] = strip
        return {"vs": self.by_strip[strip], "va": active.answered}


def _marked_drawing(observation: Observation, instance: RealWorldInstance, frame: Any) -> Drawing:
    """A real-world row: the letterboxed frame with the marks made in its original."""
    box = instance.letterboxes[frame.index]
    to_square = lambda p: tuple(float(v) for v in box.to_square(p))  # noqa: E731
    scale = sum(box.scale) / 2.0  # the letterbox keeps the aspect ratio: both axes scale alike
    shapes: list[tuple[Any, ...]] = []
    for mark in instance.marks_in(frame.image_path):
        if mark.point is not None:
            radius = mark.radius_px or observation.hit_radius_px
            shapes.append(("point", to_square(mark.point), None if radius is None else radius * scale))
        elif mark.box is not None:
            x0, y0, x1, y1 = mark.box
            shapes.append(("box", to_square((x0, y0)) + to_square((x1, y1))))
        else:
            shapes.append(("region", tuple(to_square(p) for p in mark.region or [])))
    pred = (observation.x, observation.y) if observation.x is not None and observation.y is not None else None
    return Drawing(Path(frame.file), None, "marked" if shapes else "unmarked", pred, tuple(shapes))


def image_key(drawing: Drawing, hashes: _SourceHashes) -> str:
    """The SHA-256 naming a drawing's files (source bytes + markers)."""
    payload = hashes.of(drawing.source) + json.dumps(drawing.recipe(), sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()


def image_files(images_dir: Path, key: str) -> tuple[Path, Path]:
    """``(full, thumbnail)`` paths of a drawing."""
    return images_dir / f"{key}.jpg", images_dir / f"{key}.t.jpg"


def write_drawing(drawing: Drawing, images_dir: Path, key: str) -> bool:
    """Render and save one drawing unless its files exist; True if it was drawn now."""
    full, thumb = image_files(images_dir, key)
    if full.exists() and thumb.exists():
        return False
    im = render(drawing)  # may raise IMAGE_ERRORS: nothing is written then
    _save_jpeg(im, full, 85)
    f = max(1, im.width // THUMB_SIZE)
    _save_jpeg(im.reduce(f) if f > 1 else im, thumb, 80)
    return True


def select_rows(observations: Iterable[Observation], systems: list[str], limit_per_system: int | None) -> list[Observation]:
    """The rows the gallery shows: each system's first run, in instance order, capped."""
    by_sys: dict[str, list[Observation]] = {s: [] for s in systems}
    for o in observations:
        if o.system in by_sys:
            by_sys[o.system].append(o)
    out: list[Observation] = []
    for s in systems:
        rows = by_sys[s]
        if not rows:
            continue
        first = min(o.run for o in rows)
        keep = sorted((o for o in rows if o.run == first), key=lambda o: o.instance_id)
        out.extend(keep[:limit_per_system] if limit_per_system is not None else keep)
    return out


def build_gallery(
    observations: Iterable[Observation],
    systems: list[str],
    dataset: Any,
    out_dir: str | Path,
    limit_per_system: int | None = None,
    workers: int | None = None,
    run_folders: Mapping[str, Path] | None = None,
) -> tuple[list[dict[str, Any]], GalleryStats]:
    """Draw the gallery images under ``out_dir/images`` and return the page's entry records.

    ``run_folders`` (run name -> folder) lets an active-mode row show the rendered view it
    answered in (from the run folder's ``views/``) and its trajectory on the bird's-eye card."""
    import time

    t0 = time.perf_counter()
    images_dir = Path(out_dir) / IMAGES_DIR
    images_dir.mkdir(parents=True, exist_ok=True)
    rows = select_rows(observations, systems, limit_per_system)
    sys_index = {s: i for i, s in enumerate(systems)}
    stats = GalleryStats(entries=len(rows))
    hashes = _SourceHashes()
    root = Path(dataset.root) if dataset is not None and getattr(dataset, "root", None) is not None else None
    jobs: dict[str, Drawing] = {}
    strips = _StripBook(stats, hashes)
    entries: list[dict[str, Any]] = []
    unreadable: dict[str, str] = {}  # drawing key -> why its source could not be drawn
    for o in rows:
        asked = dataset.for_run(o.run_name) if isinstance(dataset, RunSets) else dataset  # the set this row's run asked
        inst = asked.instance(o.instance_id) if asked is not None else None
        active = answered_view(o, run_folders) if run_folders is not None and inst is not None else None
        view = active.frame if active is not None else None
        question = asked_question(inst)
        asks_question = question is not None or asks_numeric_question(inst)  # a card of the question's own images
        drawing = question_drawing(inst) if asks_question else drawing_for(o, inst, view) if inst is not None else None
        key = None
        if drawing is not None and drawing.source.exists():
            try:
                key = image_key(drawing, hashes)
                jobs.setdefault(key, drawing)
            except (OSError, ReadTargetError) as exc:  # the source cannot even be read (or is a pipe)
                key = "unreadable:" + str(drawing.source)
                unreadable[key] = image_error(drawing.source, exc, root)
        else:
            stats.without_image += 1
        strip_fields = strips.fields(o.instance_id, inst) if inst is not None else {}
        frame = view if view is not None else scoring_frame(inst, o.selected_image, o.image_path) if inst is not None and not asks_question else None
        path = active.path if active is not None else ()
        from_above = birds_eye_for_row(o, inst, dataset, images_dir, frame, path) if inst is not None else None
        raw = o.raw or ""
        transcript = _transcript(row_turns(o))
        entries.append(
            {
                "s": sys_index[o.system],
                "id": o.instance_id,
                "c": o.condition,
                "d": o.direction,
                "r": o.run,
                "t": o.sentence,
                "a": raw[:MAX_RAW_CHARS] + ("…" if len(raw) > MAX_RAW_CHARS else ""),
                "st": o.status,
                "ps": o.parse_status,
                "pr": o.parse_reason[:300],
                "e": None if o.l2 is None else round(o.l2, 4),
                "es": None if o.l2_strict is None else round(o.l2_strict, 4),
                "f": o.gt_in_frame,
                "b": o.gt_behind,
                "k": o.selected_image,
                "x": o.x,
                "y": o.y,
                "img": key,
                "an": o.answered,
                "v": o.answer,
                "be": from_above,
            }
            | ({"nt": len(transcript), "tr": transcript} if transcript else {})
            | strip_fields
            | strips.views_fields(active)
            | diagnosis_fields(o, frame)
            | (choice_fields(o, question) if question is not None else {})
            | (
                {"ok": o.success, "dn": None if o.distance_norm is None else round(o.distance_norm, 4)}
                if o.protocol == "marked_hit"
                else {}
            )
        )
    n_workers = workers or min(4, os.cpu_count() or 1)

    def draw(job: tuple[str, Drawing]) -> bool | None:
        key, drawing = job
        try:
            return write_drawing(drawing, images_dir, key)
        except IMAGE_ERRORS as exc:
            unreadable[key] = image_error(drawing.source, exc, root)
            return None

    # Pillow releases the GIL while decoding and encoding, so threads overlap the heavy parts
    bad_strips: set[str] = set()

    def draw_strip(job: tuple[str, Strip]) -> None:
        key, strip = job
        try:
            write_strip(strip, images_dir, key)
        except IMAGE_ERRORS:
            bad_strips.add(key)  # a bad frame: the cards go without a strip, never the report

    with ThreadPoolExecutor(max_workers=n_workers) as pool:
        results = list(pool.map(draw, jobs.items()))
        list(pool.map(draw_strip, strips.jobs.items()))
    if bad_strips:
        for entry in entries:
            if "fs" in entry and stats.strips[entry["fs"]]["k"] in bad_strips:
                for k in ("fs", "fw"):
                    entry.pop(k, None)
    stats.drawn = sum(1 for r in results if r is True)
    stats.cached = sum(1 for r in results if r is False)
    stats.bad_images = len(unreadable)
    for entry in entries:
        why = unreadable.get(entry["img"]) if entry["img"] is not None else None
        if why is not None:
            entry["img"], entry["ie"] = None, why
    stats.seconds = time.perf_counter() - t0
    return entries, stats


def diagnosis_fields(o: Observation, frame: Any) -> dict[str, Any]:
    """An entry's diagnosis (rows scored by ``diagnose``): ``fx``, the first failing step (the
    gallery's step filter), and ``cf``, the egocentric and mirrored targets in the scored frame
    as ``[eu, ev, mu, mv]`` fractions, drawn over the card when asked; ``ar``, the frame's
    width / height when not 1 (the page crops a card's image to a square)."""
    out: dict[str, Any] = {}
    if o.fail_step is not None:
        out["fx"] = o.fail_step
    if o.egocentric_uv is not None and o.mirrored_uv is not None:
        out["cf"] = [round(v, 4) for v in (*o.egocentric_uv, *o.mirrored_uv)]
        if frame is not None and frame.camera.width != frame.camera.height:
            out["ar"] = round(frame.camera.width / frame.camera.height, 4)
    return out


def _cut(text: str | None) -> str | None:
    if text is None:
        return None
    return text[:MAX_RAW_CHARS] + ("…" if len(text) > MAX_RAW_CHARS else "")


def _transcript(stored: Sequence[tuple[str | None, str | None]]) -> list[list[str | None]]:
    """The row's turns as ``[[request text, raw answer], ...]`` (each cut at
    :data:`MAX_RAW_CHARS`); empty when no request was kept (a row of format 0 that kept none)."""
    turns = tuple(stored)  # read once (collect leaves them in the results file)
    if not any(q is not None for q, _ in turns):
        return []
    return [[_cut(q), _cut(a)] for q, a in turns]


def write_answer_chunks(
    entries: list[dict[str, Any]], out_dir: str | Path, keys: tuple[str, ...] = ("a",), chunk: int = ANSWER_CHUNK
) -> list[str]:
    """Move the raw-answer fields ``keys`` of ``entries`` into ``answers/<sha256>.js`` files.

    Each entry gets ``"ac": [file index, position]``; the page's data lists the files (by hash)
    and loads one when a card of it is opened. A file is JavaScript calling
    ``povAnswers(name, [{key: text, ...}, ...])``. Returns the file names (hashes), in order.
    """
    folder = Path(out_dir) / ANSWERS_DIR
    folder.mkdir(parents=True, exist_ok=True)
    names: list[str] = []
    for start in range(0, len(entries), chunk):
        part = entries[start : start + chunk]
        texts = [{k: e.pop(k) for k in keys if e.get(k)} for e in part]
        body = script_json(texts)
        name = hashlib.sha256(body.encode()).hexdigest()
        path = folder / f"{name}.js"
        if not path.exists():
            # the name is a hash of the content, so an existing file already holds exactly this
            script = "povAnswers(" + json.dumps(name) + "," + body + ");\n"
            write_inside(folder, path.name, script)
        for j, e in enumerate(part):
            e["ac"] = [len(names), j]
        names.append(name)
    return names
