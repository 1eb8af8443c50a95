"""Reading a config's YAML: the safe loader, the line of every key, and bounds on what a file may hold.

A config is untrusted input, and what it may ask of the reader is bounded before anything is
built: the file's size (:data:`MAX_CONFIG_BYTES`), its nesting (:data:`MAX_NESTING`), what its
aliases expand to (:data:`MAX_VALUES`, so a "billion laughs" is refused before anything expands
it). A key given twice in one mapping is an error, not "last one wins"; text that is not UTF-8
is refused; every error names the file and the line. The result, a :class:`ConfigSource`, keeps
the line of every key and list item, so later checks (:mod:`povagent.config.validation_messages`,
:mod:`povagent.config.plugin_checks`) can point at the line a problem is on.

This module only reads YAML: it must not know a pipeline's keys or validate them
(:mod:`povagent.config.models`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import yaml

from povagent.config.quoting import Loc, cut, dotted, shown
from povagent.errors import ConfigError, ReadTargetError
from povagent.files.confined_read import read_regular

#: Largest config file read (a pipeline is a few hundred bytes; a sweep with routers a few KiB).
MAX_CONFIG_BYTES = 1024 * 1024
#: Deepest nesting of mappings and lists (a pipeline needs about 6).
MAX_NESTING = 64
#: Most values a document may hold once its aliases are expanded.
MAX_VALUES = 50_000


@dataclass
class ConfigSource:
    """A YAML document: its file name, data, and the line of every key and list item."""

    file: str
    data: Any
    lines: dict[Loc, int] = field(default_factory=dict)
    #: The folder its ``.py`` plugins are read from (default: the file's own folder; a document
    #: that is no file, ``<pipeline mapping>``, has none).
    folder: Path | None = None

    def plugin_folder(self) -> Path | None:
        """The folder this document may load ``.py`` plugins from (see :mod:`povagent.config.plugin_rule`)."""
        if self.folder is not None:
            return self.folder
        return None if self.file.startswith("<") else Path(self.file).parent

    def line_of(self, loc: Iterable[Any]) -> int | None:
        """The line of the deepest known prefix of ``loc`` (1-based), if any."""
        loc = tuple(loc)
        while loc:
            if loc in self.lines:
                return self.lines[loc]
            loc = loc[:-1]
        return None

    def where(self, loc: Iterable[Any] = ()) -> str:
        """``file, line N`` (or just the file)."""
        line = self.line_of(loc)
        return f"{self.file}, line {line}" if line else self.file


def _record_lines(file: str, node: yaml.Node, loc: Loc, lines: dict[Loc, int], seen: set[int] | None = None) -> None:
    """Record the line of every key and list item; a key twice in one mapping is an error.

    A node reached again through an alias is not walked again: its lines are known from where
    it was written, and walking every alias path is what a "billion laughs" exploits.
    """
    seen = set() if seen is None else seen
    if id(node) in seen:
        return
    seen.add(id(node))
    if isinstance(node, yaml.MappingNode):
        first: dict[str, int] = {}
        for key_node, value_node in node.value:
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            if key is None or key_node.tag == "tag:yaml.org,2002:merge":
                continue  # "<<: *base" merges keys: an explicit key beside it overrides, as YAML says
            line = key_node.start_mark.line + 1
            if key in first:
                section = dotted(loc) if loc else "the top level"
                raise ConfigError(
                    f"{file}, line {line}: key {shown(key)} appears twice in {section} (first at line {first[key]}); "
                    "keep one (YAML would silently use the last)"
                )
            first[key] = line
            lines[loc + (key,)] = line
            _record_lines(file, value_node, loc + (key,), lines, seen)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            lines[loc + (i,)] = item.start_mark.line + 1
            _record_lines(file, item, loc + (i,), lines, seen)


def _check_shape(text: str, file: str) -> None:
    """Refuse, from the event stream and before anything is built, a document nested deeper than
    :data:`MAX_NESTING` or whose aliases expand it beyond :data:`MAX_VALUES` values (also an
    alias inside its own anchor). Parse errors propagate as :class:`yaml.YAMLError`."""
    loader = yaml.SafeLoader(text)
    try:
        sizes: dict[str, int] = {}  # anchor -> values it expands to
        open_frames: list[list[Any]] = []  # [anchor, values so far] per open mapping or list
        total = 0
        while loader.check_event():
            event = loader.get_event()
            line = event.start_mark.line + 1 if event.start_mark is not None else None
            where = f"{file}, line {line}" if line else file
            added = 0
            if isinstance(event, yaml.AliasEvent):
                anchor = event.anchor or ""  # an alias always names its anchor
                if any(frame[0] == anchor for frame in open_frames):
                    raise ConfigError(f"{where}: alias *{cut(anchor)} refers to its own anchor (a recursive alias)")
                added = sizes.get(anchor, 1)
            elif isinstance(event, yaml.ScalarEvent):
                added = 1
                if event.anchor:
                    sizes[event.anchor] = 1
            elif isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                if len(open_frames) >= MAX_NESTING:
                    raise ConfigError(f"{where}: nested more than {MAX_NESTING} levels deep; a config needs a handful")
                open_frames.append([event.anchor, 1])
                total += 1
                continue
            elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                anchor, count = open_frames.pop()
                if anchor:
                    sizes[anchor] = count
                if open_frames:
                    open_frames[-1][1] += count
                continue
            else:
                continue
            if open_frames:
                open_frames[-1][1] += added
            total += added
            if total > MAX_VALUES:
                raise ConfigError(
                    f"{where}: aliases (*name) expand this document to more than {MAX_VALUES:,} values; "
                    "a config needs far fewer (is an anchor repeated inside another on purpose?)"
                )
    finally:
        loader.dispose()


def _yaml_error(exc: yaml.YAMLError, text: str, file: str) -> ConfigError:
    """A parse error as a one-line message with the line."""
    if isinstance(exc, yaml.reader.ReaderError):
        line = text.count("\n", 0, exc.position) + 1
        return ConfigError(f"{file}, line {line}: not valid YAML: control character #x{exc.character:04x} (a config is plain text)")
    mark = getattr(exc, "problem_mark", None)
    where = f"{file}, line {mark.line + 1}" if mark is not None else file
    problem = getattr(exc, "problem", None) or str(exc)
    return ConfigError(f"{where}: not valid YAML: {cut(problem)}")


def parse_yaml(text: str, file: str) -> ConfigSource:
    """Parse YAML with the safe loader, keeping the line of every key; errors name the line.

    The document is bounded before it is built (size, nesting, alias expansion) and a key
    given twice in one mapping is an error.
    """
    if len(text) > MAX_CONFIG_BYTES:
        raise ConfigError(f"{file}: {len(text) / 1048576:.1f} MiB of text; a config is at most {MAX_CONFIG_BYTES // 1048576} MiB")
    try:
        _check_shape(text, file)
    except yaml.YAMLError as exc:
        raise _yaml_error(exc, text, file) from None
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        lines: dict[Loc, int] = {}
        if node is not None:
            # before construction: building a mapping folds "<<" merges into it
            _record_lines(file, node, (), lines)
        data = loader.construct_document(node) if node is not None else None
    except yaml.YAMLError as exc:
        raise _yaml_error(exc, text, file) from None
    finally:
        loader.dispose()
    return ConfigSource(file, data, lines)


def read_yaml(path: str | os.PathLike[str]) -> ConfigSource:
    """Read and parse a YAML file (a missing, oversized or non-UTF-8 file is a :class:`ConfigError`)."""
    p = Path(path)
    try:
        if p.is_dir():
            raise ConfigError(f"{p}: is a folder, not a YAML file")
        # a pipe or a device is refused, not waited on (a run folder's config.yaml is anyone's)
        raw = read_regular(p, MAX_CONFIG_BYTES, what="config")
    except ReadTargetError as exc:
        raise ConfigError(f"{exc} (is this the right file?)") from None
    except FileNotFoundError:
        raise ConfigError(f"{p}: file not found") from None
    except OSError as exc:
        raise ConfigError(f"{p}: cannot be read: {exc.strerror or exc}") from None
    return yaml_source(p, raw)


def yaml_source(path: str | os.PathLike[str], raw: bytes) -> ConfigSource:
    """Parse the bytes read from the YAML file at ``path`` (a text that is not UTF-8 is a
    :class:`ConfigError`): for a reader that read the file already (a run folder's)."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not UTF-8 text (byte {exc.start} is 0x{raw[exc.start]:02x}); a config is a YAML text file saved as UTF-8") from None
    return parse_yaml(text, str(path))
