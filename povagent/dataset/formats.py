"""Dataset formats: what a set's files are and how povagent reads and scores them, as a plugin.

A format is a :class:`DatasetFormat` a plugin contributes through the
``register_dataset_formats`` hook, the built-ins (the POVBench release, generated sets, the
real-world set, ViewSpatial-Bench, MindCube, 3DSRBench) exactly as a third party's would be.
It names its reader, how a problem names one of its records, the answer type its records ask
for, its official rule (a parser and a scorer, each a registered plugin), the prompt profile its
questions are asked in, where it comes from (``repo@commit``) and under which licence, and its
row in the docs' table of sets. Everything that used to keep a list of formats (the config's
``dataset.format``, ``--help``, ``povagent validate``, the default parser and scorers, the
report's loader, the docs) asks the plugin host instead (:func:`registered_formats`).

Only the description of a format lives here; nothing here reads a file or knows a plugin.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Mapping

if TYPE_CHECKING:
    from povagent.dataset.problems import Problem
    from povagent.dataset.set_interface import EvaluationSet
    from povagent.plugins import PluginHost


@dataclass(frozen=True)
class FormatRead:
    """What a reader is handed: the path the user named (``dataset.path``, or
    ``povagent validate``'s argument) and how to read it."""

    path: Path
    #: The folder the set's image paths are relative to and confined to (``dataset.images``;
    #: ``None``: the reader's default, usually the file's folder).
    images: Path | None = None
    #: Stop at the first bad record instead of naming it in ``problems`` and going on.
    strict: bool = False
    #: Whether images are opened as the set is read (the report reads ground truth only).
    check_images: bool = True
    #: The format's own options (``dataset.options`` in a pipeline: e.g. ``{frames: 16}``; the
    #: config admits only the format's :attr:`DatasetFormat.option_names`); a reader refuses a
    #: bad value with :class:`~povagent.errors.DatasetError` naming the file.
    options: Mapping[str, Any] = field(default_factory=dict)
    #: Where a validator puts what leaves the set valid (``povagent validate`` prints them on
    #: stderr); ``None``: nobody asks.
    warnings: list[Problem] | None = None


@dataclass(frozen=True)
class DocsRow:
    """A format's row in the docs' table of sets (``docs/reference/datasets.md``, generated)."""

    #: The set's name as its authors write it (``ViewSpatial-Bench``).
    name: str
    #: Where to get it, in Markdown (``[`lidingm/ViewSpatial-Bench`](https://huggingface.co/...)``).
    where: str
    #: What ``dataset.path`` names, in Markdown (``the JSON list of questions``).
    path: str
    #: The docs page that says where to get it and how to run it (relative to ``docs/``).
    how_to: str


@dataclass(frozen=True)
class PromptProfile:
    """How a set words its prompt: the text around the images, in the set's published wording."""

    name: str
    #: The text asked, from an instance's question (a :class:`~povagent.answers.choice_question.ChoiceQuestion`
    #: for a choice set): ``text(question) -> str``.
    text: Callable[[Any], str]
    #: Where the wording comes from (``lmms-eval viewspatial_doc_to_text @ 75571cfe``).
    source: str
    #: The images go where the text has an ``<image>`` marker (MindCube), instead of all first.
    interleaved: bool = False


@dataclass(frozen=True)
class DatasetFormat:
    """One dataset format (see the module docstring). ``key`` is what ``dataset.format`` and
    ``povagent validate --format`` name."""

    key: str
    #: One line: what the set is (``povagent plugins`` shows it).
    description: str
    #: Reads the set: ``read(FormatRead) -> EvaluationSet`` (its instances, the records it left
    #: out in ``problems``); a file that cannot be read at all raises
    #: :class:`~povagent.errors.DatasetError` naming the file.
    read: Callable[[FormatRead], EvaluationSet]
    #: How a problem names a record: ``record_id("12") -> "$[12]"`` (a position in a JSON list),
    #: ``"record 12"`` (an id), ``"house_3/pair_7"``.
    record_id: Callable[[str], str]
    #: The answer type every record asks for (a registered ``answer_type``: ``point``, ``choice``).
    answer_type: str
    #: The official rule: the parser (a registered parser) and scorer (a registered scorer) a
    #: pipeline on this format gets when it names none. A test fails when either is not registered.
    official_parser: str
    official_scorer: str
    #: Where the set and its rule come from (``ZJU-REAL/ViewSpatial-Bench@2e85a5e4...``).
    source: str
    #: The set's licence as its authors publish it (``CC BY 4.0``; ``unknown`` when unpublished).
    licence: str
    docs_row: DocsRow
    #: The prompt profile its questions are asked in (its records name it: ``ChoiceQuestion.profile``
    #: is its ``name``); ``None``: the strategy's own wording (POVBench's point prompts).
    prompt_profile: PromptProfile | None = None
    #: Lists every problem of a set for ``povagent validate --format KEY`` (``None``: read it
    #: with :attr:`read` and list its ``problems``, a file that cannot be read being one problem).
    validate: Callable[[FormatRead], list[Problem]] | None = None
    #: For a format found by looking at a folder rather than named (``dataset.format`` absent):
    #: whether the folder is one of this format's sets. Checked in :attr:`detect_order` order.
    detect: Callable[[Path], bool] | None = None
    #: Lower is asked first when ``dataset.format`` is absent (the POVBench release, which
    #: takes any folder, is asked last).
    detect_order: int = 100
    #: ``dataset.options`` keys the reader accepts (anything else is refused at config load).
    option_names: tuple[str, ...] = ()

    def problems_of(self, request: FormatRead) -> list[Problem]:
        """Every problem of the set ``request`` names: :attr:`validate`'s, or the records
        :attr:`read` left out (a file it cannot read at all is one problem)."""
        if self.validate is not None:
            return self.validate(request)
        from povagent.dataset.problems import Problem
        from povagent.errors import DatasetError

        try:
            return list(self.read(request).problems)
        except DatasetError as exc:
            return [Problem(str(request.path), "", str(exc).removeprefix(f"{request.path}: "))]


def registered_format(host: PluginHost, key: str) -> DatasetFormat:
    """The dataset format registered as ``key`` on ``host`` (``register_dataset_formats``);
    :class:`~povagent.errors.PluginError` for an unknown key (with the nearest), or for a plugin
    that registered something else, an incomplete format, or one under another key."""
    from povagent.errors import PluginError

    entry = host.entry("format", key)
    found = check_format(entry.factory, entry.source)
    if found.key != key:
        raise PluginError(f"{entry.source}: dataset format registered as {key!r} has key {found.key!r}")
    return found


def registered_formats(host: PluginHost) -> dict[str, DatasetFormat]:
    """Every dataset format registered on ``host``, by key, sorted."""
    return {key: registered_format(host, key) for key in host.names("format")}


def missing_rules(host: PluginHost, keys: Iterable[str] | None = None) -> list[str]:
    """One line per registered format (of ``keys``; default: all) whose answer type, official
    parser or official scorer no plugin registers, or whose official parser does not read its
    answer type (empty: each can be read and scored by its own rule)."""
    found = []
    for key in host.names("format") if keys is None else keys:
        fmt = registered_format(host, key)
        source = host.entry("format", key).source
        for kind, name in (("answer_type", fmt.answer_type), ("parser", fmt.official_parser), ("scorer", fmt.official_scorer)):
            if name not in host.names(kind):
                found.append(f"dataset format {key!r} ({source}) names {kind} {name!r}, which no plugin registers")
        if fmt.official_parser in host.names("parser") and fmt.answer_type in host.names("answer_type"):
            reads = getattr(host.entry("parser", fmt.official_parser).factory, "answer_types", None)
            if reads is not None and fmt.answer_type not in reads:
                found.append(f"dataset format {key!r} ({source}): its official parser {fmt.official_parser!r} does not read {fmt.answer_type!r} answers")
    return found


def check_format(fmt: object, source: str) -> DatasetFormat:
    """``fmt`` as a :class:`DatasetFormat`, or :class:`~povagent.errors.PluginError` naming the
    plugin that registered something else or an incomplete one."""
    from povagent.errors import PluginError

    if not isinstance(fmt, DatasetFormat):
        raise PluginError(f"{source}: registered a dataset format that is a {type(fmt).__name__}, not a povagent.dataset.formats.DatasetFormat")
    empty = [name for name in ("key", "answer_type", "official_parser", "official_scorer", "source", "licence") if not getattr(fmt, name)]
    if empty:
        raise PluginError(f"{source}: dataset format {fmt.key!r} leaves {', '.join(empty)} empty")
    return fmt


__all__ = ["DatasetFormat", "DocsRow", "FormatRead", "PromptProfile", "check_format", "missing_rules", "registered_format", "registered_formats"]
