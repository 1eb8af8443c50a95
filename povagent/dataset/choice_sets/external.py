"""An external multiple-choice set loaded into povagent's instances: what the three readers share.

A reader (:mod:`.viewspatial`, :mod:`.mindcube`, :mod:`.srbench3d`) turns each record of its
set's published file into an :class:`Item` (its id, a :class:`~povagent.answers.choice_question.ChoiceQuestion`
and the images it shows) or into :class:`~povagent.dataset.problems.Problem` lines naming the file,
the record and the field. This module makes the items runnable: every image path is confined to
the folder the set's file is in (:func:`~povagent.dataset.paths.confined`; an absolute path, a
``..`` that climbs out or a symlink leading out is a problem and never opened), every image is
checked sound once (:func:`~povagent.dataset.image_files.image_problem`), and each item becomes an
:class:`~povagent.dataset.instances.Instance` with no direction, no condition and NaN 3D fields
(the set has none: only a choice scorer can score it).

This module must not parse a set's file (the readers do) nor word a prompt (the strategy's
profiles do).
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence

from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.numeric_question import NumericQuestion
from povagent.dataset.image_files import ImageFileError, inspect_image_file
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.json_files import TooDeepError, loads_dataset_json
from povagent.dataset.paths import OutsideDatasetError, confined, dataset_root, shown
from povagent.dataset.problems import Problem, not_text_problems
from povagent.dataset.release_models import Condition, Direction
from povagent.errors import ConfigError
from povagent.geometry.camera import Camera


@dataclass(frozen=True)
class Item:
    """One record of a set as read: its id (unique in the set), its question and the images it
    shows, each a path relative to the set's folder (or, for 3DSRBench's embedded images, a file
    the reader wrote into its cache: ``embedded=True``)."""

    id: str
    question: ChoiceQuestion
    images: tuple[str, ...]
    embedded: bool = False


def image_camera(width: int, height: int) -> Camera:
    """The camera of an image nobody posed: only its size is real (a strategy reads the frame
    size from it; nothing may project through it)."""
    return Camera((0.0, 0.0, 0.0), 0.0, 0.0, 100.0, width, height)


def item_frames(
    root: Path, item: Item, file: str, where: str, problems: list[Problem], cache: Path | None = None, lookups: ImageLookups | None = None,
) -> tuple[Frame, ...] | None:
    """The item's images as frames, each confined to ``root`` and checked sound; ``None`` (and
    a problem naming ``file``, the record ``where`` and the image field) when any is not.
    ``lookups``: the set's images looked up so far (each image path is resolved and checked
    once per set, its frame shared by the items showing it); default: none."""
    lookups = lookups if lookups is not None else ImageLookups(root)
    frames: list[Frame] = []
    for index, rel in enumerate(item.images):
        found = lookups.frame(index, rel, cache if item.embedded else None)
        if isinstance(found, str):
            problems.append(Problem(file, f"{where}.images[{index}]", found))
            return None
        frames.append(found)
    return lookups.shared(tuple(frames))


class ImageLookups:
    """A set's image paths, each resolved inside ``root`` (:func:`~povagent.dataset.paths.confined`)
    and checked sound once: a set of 10,000 items over 40 images resolves 40 paths, not 10,000
    (and shares 40 frames). A path that is refused is refused for every item naming it."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.real_root = dataset_root(root)
        self._frames: dict[tuple[int, str, Path | None], Frame | str] = {}
        self._shown: dict[tuple[int, ...], tuple[Frame, ...]] = {}

    def shared(self, frames: tuple[Frame, ...]) -> tuple[Frame, ...]:
        """``frames``, as one tuple for every item showing the same images (up to 4,096 lists)."""
        # known by the frames' identities (a frame a set's items share is one object: see
        # :meth:`frame`), not by hashing each frame's fields and camera again for every item;
        # the tuple kept holds the frames, so an identity stands for one frame while it is kept
        key = tuple(map(id, frames))
        known = self._shown.get(key)
        if known is None and len(self._shown) < 4096:
            known = self._shown.setdefault(key, frames)
        return frames if known is None else known

    def frame(self, index: int, rel: str, embedded_in: Path | None) -> Frame | str:
        """The frame at position ``index`` showing ``rel`` (an image written into the reader's
        cache ``embedded_in``, else a path inside ``root``), or why it cannot be shown."""
        key = (index, rel, embedded_in)
        found = self._frames.get(key)
        if found is None:
            found = self._frames[key] = self._look_up(index, rel, embedded_in)
        return found

    def _look_up(self, index: int, rel: str, embedded_in: Path | None) -> Frame | str:
        try:
            path = embedded_in / rel if embedded_in is not None else confined(self.real_root, self.root, rel)
            facts = inspect_image_file(path)
        except OutsideDatasetError as exc:
            return str(exc)
        except ImageFileError as exc:
            return f"image {shown(rel)} {exc}"
        return Frame(index, rel, path, image_camera(facts.width, facts.height))


#: The 3D target of every item: none (one tuple for all of them).
_NO_TARGET = (float("nan"),) * 3


def choice_instance(set_name: str, item: Item, frames: tuple[Frame, ...], nowhere: Any = None) -> Instance:
    """The runnable instance of one item: id ``<set>/<record id>``, no direction or condition.
    ``nowhere``: the unknown object to stand for its observer and anchor (one a set may share)."""
    return question_instance(set_name, item.id, item.question, frames, nowhere)


def question_instance(
    set_name: str, record_id: str, question: Any, frames: tuple[Frame, ...], nowhere: Any = None
) -> Instance:
    """The runnable instance of one record of an external set, asking ``question``: a
    :class:`ChoiceQuestion` (``Instance.question``) or a numeric one (``Instance.numeric``). It has
    no direction, condition or target; ``nowhere`` (the unknown object, one a set may share)
    stands for its observer and anchor, and its first frame's camera for the observer's."""
    if nowhere is None:  # (imported here, and only when needed: every record of a set comes through)
        from povagent.dataset.realworld_set import unknown_object

        nowhere = unknown_object()
    camera = frames[0].camera if frames else image_camera(1, 1)
    return Instance(
        house_id=set_name,
        pair_id=record_id,
        direction=None,
        condition=None,
        sentence=question.question,
        frames=frames,
        target=_NO_TARGET,
        observer_object=nowhere,
        anchor_object=nowhere,
        observer_camera=camera,
        question=question if isinstance(question, ChoiceQuestion) else None,
        numeric=question if isinstance(question, NumericQuestion) else None,
    )


@dataclass
class ChoiceSet:
    """A loaded external multiple-choice set, with the interface the runner uses
    (:class:`~povagent.dataset.set_interface.EvaluationSet`).

    ``root`` is the folder of the set's file (images are confined to it); ``houses`` holds one
    entry, the set's name, so a ``houses`` filter naming it selects every item. ``problems`` are
    the records left out, each one line naming file, record and field.
    """

    root: Path
    file: Path
    name: str
    problems: list[Problem] = field(default_factory=list)
    _instances: list[Instance] = field(default_factory=list, repr=False)
    _by_id: dict[str, Instance] = field(default_factory=dict, repr=False)
    #: where embedded images were written (3DSRBench's base64 cells); removed with the set
    cache_dir: Path | None = None

    @property
    def houses(self) -> Mapping[str, Path]:
        """The one "house": the set's name, with its file."""
        return {self.name: self.file}

    def instances(
        self,
        conditions: Iterable[Condition | str] | None = None,
        directions: Iterable[Direction | str] | None = None,
        houses: Iterable[str] | None = None,
    ) -> Sequence[Instance]:
        """Every item in file order. An item has no condition and no direction, so a filter on
        either selects none; a ``houses`` filter selects all or none by the set's name."""
        if conditions is not None or directions is not None:
            return []
        if houses is not None and self.name not in set(houses):
            return []
        return list(self._instances)

    def instance(self, id_: str) -> Instance | None:
        """The item with id ``<set>/<record id>`` (rescore asks once per row: an index, kept)."""
        if len(self._by_id) != len(self._instances):
            self._by_id = {i.id: i for i in self._instances}
        return self._by_id.get(id_)

    def check_scorers(self, scorers: Mapping[str, Any]) -> None:
        """Refuse scorers that need POVBench's point ground truth (the runner asks before any
        request): a multiple-choice item has a gold label, no 3D target and no marks. A scorer
        says so itself (``Scorer.needs_3d_target``, or a point protocol: ``Scorer.protocol``)."""
        refused = sorted(name for name, scorer in scorers.items() if getattr(scorer, "needs_3d_target", False) or getattr(scorer, "protocol", None) is not None)
        if refused:
            raise ConfigError(
                f"{self.file}: scorer {', '.join(refused)} needs a point ground truth, and a multiple-choice set "
                "has a gold label: use scorers: [choice] (or the set's own, see docs/how-to/perspective-sets.md)"
            )


#: The longest record line a JSONL or TSV set may hold (a 3DSRBench line embeds its image).
MAX_RECORD_LINE_BYTES = 64 << 20


def record_lines(path: Path, what: str, problems: list[Problem]) -> Iterable[tuple[int, str]]:
    """The text lines of a line-per-record file, numbered from 1, each read with its bound
    (:data:`MAX_RECORD_LINE_BYTES`). A line longer than that, or not UTF-8, is a problem; an
    over-long line ends the reading (what follows it cannot be told apart from its rest)."""
    from povagent.files.confined_read import open_regular

    with open_regular(path, what=what) as handle:
        for number, raw in enumerate(iter(lambda: handle.readline(MAX_RECORD_LINE_BYTES + 1), b""), start=1):
            if len(raw) > MAX_RECORD_LINE_BYTES:
                problems.append(
                    Problem(str(path), f"line {number}", f"longer than {MAX_RECORD_LINE_BYTES} bytes; this line and the rest of the file are not read")
                )
                return
            try:
                text = raw.decode("utf-8")
            except UnicodeDecodeError as exc:
                problems.append(Problem(str(path), f"line {number}", f"byte 0x{raw[exc.start]:02x} at column {exc.start + 1} is not UTF-8; record left out"))
                continue
            if text.strip():
                yield number, text.rstrip("\r\n")


#: How an embedded image's first bytes tell its kind (the cached file's extension).
_IMAGE_SIGNATURES = {b"\x89PNG\r\n\x1a\n": "png", b"\xff\xd8\xff": "jpg"}


def cached_image(data: bytes, cache: Path, not_an_image: str) -> str:
    """Write an embedded image's ``data`` into ``cache`` and give its file name (the file is then
    checked like any image); :class:`ValueError` ``not_an_image`` when it is neither a PNG nor a JPEG."""
    kind = next((ext for sig, ext in _IMAGE_SIGNATURES.items() if data.startswith(sig)), None)
    if kind is None:
        raise ValueError(not_an_image)
    cache.mkdir(parents=True, exist_ok=True)
    # named by content, never by text from the file (an id, a qid): the same image is one file
    name = f"{hashlib.sha256(data).hexdigest()[:32]}.{kind}"
    if not (cache / name).is_file():
        (cache / name).write_bytes(data)
    return name


def record_id_problem(value: object) -> str | None:
    """Why ``value`` cannot be a record id (an instance id is ``<set>/<record id>``), or ``None``."""
    if not isinstance(value, str) or not value:
        return f"must be a non-empty string, got {value!r:.60}"
    if "/" in value or "#" in value:
        return f"{shown(value)} holds '/' or '#', which an instance id cannot"
    return None


def text_problems(file: str, where: str, record: Any) -> list[Problem]:
    """The release reader's rule (:func:`~povagent.dataset.problems.not_text_problems`) on one
    record: a problem per string holding a lone surrogate, named ``<where>.<json path>``. A
    record with one is left out (no row, prompt or report could hold its text)."""
    return [Problem(p.file, where + p.json_path.removeprefix("$"), p.message) for p in not_text_problems(file, record)]


def json_list(file: Path, what: str) -> tuple[list[Any] | None, list[Problem]]:
    """A JSON file holding a list of records (read regular-file-only and bounded), or ``None``
    and the one problem saying why it is not: not UTF-8, not JSON, nested too deep, not a list."""
    data, problems, _ = json_text_list(file, what)
    return data, problems


#: A JSON escape of a surrogate code point (``\\ud800`` to ``\\udfff``): the only way a file of
#: UTF-8 text (surrogates are not UTF-8) gives parsed strings holding a lone surrogate.
_SURROGATE_ESCAPE = re.compile(r"\\u[dD][89a-fA-F]")


def json_text_list(file: Path, what: str) -> tuple[list[Any] | None, list[Problem], bool]:
    """:func:`json_list`, and whether its records surely hold only text (no lone surrogate: see
    :func:`~povagent.dataset.problems.not_text_problems`), told from the file's text: no
    surrogate is escaped in it (a search of the text, where writing the records again cost a
    10,000-record set ~20 ms). ``False``: the records may hold one (an escaped pair is text too).
    """
    from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular

    name = str(file)
    try:
        text = read_regular(file, MAX_DOCUMENT_BYTES, what=what).decode("utf-8")
        data = loads_dataset_json(text)
    except TooDeepError as exc:
        return None, [Problem(name, "", str(exc))], False
    except UnicodeDecodeError as exc:
        return None, [Problem(name, "", f"not UTF-8 text ({exc.reason} at byte {exc.start})")], False
    except json.JSONDecodeError as exc:
        return None, [Problem(name, "", f"not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}")], False
    if not isinstance(data, list):
        return None, [Problem(name, "", f"the file must hold a JSON list of records (got {type(data).__name__})")], False
    return data, [], "\\u" not in text or _SURROGATE_ESCAPE.search(text) is None


def jsonl_records(file: Path, what: str, problems: list[Problem]) -> Iterator[tuple[str, Any]]:
    """Each line's record of a JSON-lines file, named ``line N``; a line that is not JSON (or
    nests too deep) is a problem, in line order with the ones the caller finds."""
    for number, line in record_lines(file, what, problems):
        where = f"line {number}"
        try:
            record = loads_dataset_json(line)
        except json.JSONDecodeError as exc:
            problems.append(Problem(str(file), where, f"not valid JSON: {exc.msg} at column {exc.colno}"))
            continue
        except TooDeepError as exc:
            problems.append(Problem(str(file), where, str(exc)))
            continue
        yield where, record


def sound_items(
    file: Path, records: Iterable[tuple[str, Any]], make: Callable[[Any, str], Any], problems: list[Problem], reused: str = "is used by an earlier record"
) -> list[Any]:
    """The items ``make(record, where)`` builds from ``records``, in order; a record holding text
    no output can hold, one ``make`` refuses (it returns ``(where, message)``) or one whose id an
    earlier item took (its problem: the id, then ``reused``) is a problem and left out."""
    items: list[Any] = []
    seen: set[str] = set()
    for where, record in records:
        not_text = text_problems(str(file), where, record)
        if not_text:  # the rule the release reader holds: a lone surrogate is not text
            problems.extend(not_text)
            continue
        item = make(record, where)
        if isinstance(item, tuple):
            problems.append(Problem(str(file), *item))
        elif item.id in seen:
            problems.append(Problem(str(file), f"{where}.id", f"{shown(item.id)} {reused}; this one left out"))
        else:
            seen.add(item.id)
            items.append(item)
    return items
