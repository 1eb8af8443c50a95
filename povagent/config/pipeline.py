"""Pipeline and sweep YAML: typed models, safe loading, and errors that say where and what.

A pipeline YAML (every key but ``dataset``, ``output`` and one of ``backend``/``model`` has a
default)::

    plugins: [my_pkg.my_plugin]          # extra plugin modules: installed dotted names, or .py paths
                                         # inside this file's folder (see docs/security.md)
    dataset: {path: data/povbench}       # or {generate: {houses: 3, seed: 0, frames: 30, out: data/gen}}
                                         # or {hub: owl-owl/POVBench, revision: main} (the release,
                                         # fetched into the Hugging Face cache; bounded by
                                         # download: {deadline_s: 3600, max_file_mib: 64, max_total_mib: 4096})
                                         # (generate also takes judge: NAME or {name, options})
                                         # strict: true stops at a bad house (default: report, skip)
    instances:                           # which instances to run (default: all)
      conditions: [a, b, c]              # a/inferred, b/stated, c/given
      directions: [right, left, front, up]
      houses: null                       # list of house ids
      sample: null                       # random sample of N instances (seeded), kept in dataset order
      seed: 0
      limit: null                        # the first N instances (after sampling)
    backend: {name: litellm, options: {model: openai/gpt-5.4, api_key_env: OPENAI_API_KEY}}
    # model: gpt-5.4                     # or a model profile name instead of backend:
    strategy: {name: basic, options: {}} # a bare name works too: "strategy: spatial-cot"
    parser: json                         # default: the model profile's parser, else json
    scorers: [official]
    runs: 3                              # repeats, run indices 0..2 (or a list of indices)
    concurrency: 16                      # requests in flight
    retry: {attempts: 5, initial_wait: 1.0, max_wait: 60.0}
    timeout: 120                         # seconds per request
    stop_after_failures: 10              # consecutive infra_error rows that stop the run (0: never)
    cache: true                          # true (default: <output>/cache.sqlite), false, or a path
    images: {max_mb: 256}                # memory bound of the run's image store; how images travel:
                                         # transport: inline (base64, default) | file | http
                                         # (http: bind: 127.0.0.1:8765, public_url: http://host:8765)
    output: runs/my-run

Relative paths are relative to the working directory. A typo in a key or a plugin name fails
before any request, naming the file, the line and the nearest valid name.

A config is untrusted input too, and what it may ask for is bounded: the file's size
(:data:`MAX_CONFIG_BYTES`), its nesting (:data:`MAX_NESTING`), what its aliases expand to
(:data:`MAX_VALUES`, so a "billion laughs" is refused before anything expands it), repeats
(:data:`MAX_RUNS`), retries and waits (finite, at most :data:`MAX_WAIT_S`), the request timeout
and concurrency. A key given twice is an error, not "last one wins"; text that is not UTF-8 is
refused; values quoted back in messages are cut short.

This module reads and checks configs; it must not run anything (see :mod:`povagent.run.runner`).
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Literal, Mapping, Union, get_args, get_origin

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from povagent.cluster.spec import parse_cluster_spec  # pure: no Dask import
from povagent.config.plugin_rule import allowed_plugins
from povagent.config.profiles import near_profile
from povagent.config.retry_policy import RetryPolicy
from povagent.dataset.hub_limits import DownloadLimits
from povagent.dataset.models import Condition, Direction
from povagent.errors import ClusterError, ConfigError, PluginError
from povagent.exchange.image_server import parse_bind
from povagent.plugins import PluginHost, did_you_mean, get_plugin_host, unknown_name_message
from povagent.run.logs import ENV_NAME_WANTED, Redactor

Loc = tuple[Any, ...]

#: Largest config file read (a pipeline is a few hundred bytes; a sweep with routers a few KiB).
MAX_CONFIG_BYTES = 1024 * 1024
#: Deepest nesting of mappings and lists (a pipeline needs about 6).
MAX_NESTING = 64
#: Most values a document may hold once its aliases are expanded.
MAX_VALUES = 50_000
#: Most repeats a pipeline may ask for (``runs: N`` or a list of N indices); the paper uses 3.
MAX_RUNS = 100
#: Longest retry wait and request timeout, in seconds.
MAX_WAIT_S = 3600.0
#: Most attempts per request, and most requests in flight.
MAX_ATTEMPTS = 100
MAX_CONCURRENCY = 1024
#: Longest user value quoted back in a message.
_SHOWN = 80


def shown(value: Any) -> str:
    """``repr(value)``, cut to a readable length (a hostile config may hold megabytes)."""
    text = repr(value) if not isinstance(value, str) else repr(value if len(value) <= _SHOWN else value[:_SHOWN] + "...")
    return text if len(text) <= _SHOWN + 10 else text[:_SHOWN] + "..."


def _cut(name: str) -> str:
    """A user-written name cut for messages and name suggestions (difflib is quadratic)."""
    return name if len(name) <= _SHOWN else name[:_SHOWN] + "..."


# -- models -------------------------------------------------------------------------------------
class _Strict(BaseModel):
    """Unknown keys are errors (a typo must never be silently ignored); numbers are finite
    (``.inf`` is a wait that never ends)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


def _a_folder_path(value: Path) -> Path:
    """``value`` may become a folder: neither it nor any existing parent is a file."""
    for p in (value, *value.parents):
        if p.exists():
            if not p.is_dir():
                where = "names" if p == value else f"is under {p}, which is"
                raise ValueError(f"{where} an existing file, not a folder: choose a folder path for the run's files")
            break
    return value


class ComponentSpec(_Strict):
    """A plugin by name with its options (a bare string is the name with no options)."""

    name: str = Field(min_length=1)
    options: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _bare_name(cls, value: Any) -> Any:
        return {"name": value} if isinstance(value, str) else value


class GenerateSpec(_Strict):
    """Generate a synthetic dataset (once) into ``out``.

    ``judge`` is the surface judge by its registered name (``register_judges``), with options:
    ``judge: physical-rules`` (the default) or ``judge: {name: vlm, options: {...}}``; the
    pipeline's ``plugins:`` are loaded first, so a judge plugin listed there can be named.
    """

    houses: int = Field(3, ge=1)
    seed: int = 0
    frames: int = Field(30, ge=1)
    out: Path
    judge: ComponentSpec = Field(default_factory=lambda: ComponentSpec(name="physical-rules"))


class DatasetSpec(_Strict):
    """Where the instances come from: an existing release-layout folder, a generator spec, or
    a dataset repository on the Hugging Face Hub (``hub``, at ``revision``)."""

    path: Path | None = None
    generate: GenerateSpec | None = None
    #: A Hub dataset repository (``owl-owl/POVBench``), fetched into the Hugging Face cache
    #: (see :mod:`povagent.dataset.hub`). A run fills in ``path`` (the local copy) and pins
    #: ``revision`` to the commit it used, in the run folder's ``config.yaml``.
    hub: str | None = None
    #: Branch, tag or commit of ``hub`` (default: ``main``).
    revision: str | None = Field(None, min_length=1)
    #: Bounds of fetching ``hub``: ``{deadline_s, max_file_mib, max_total_mib}`` (see
    #: :mod:`povagent.dataset.hub_limits` for the defaults).
    download: DownloadLimits | None = None
    #: Stop at the first bad house or pair instead of reporting it and going on.
    strict: bool = False

    @model_validator(mode="before")
    @classmethod
    def _bare_path(cls, value: Any) -> Any:
        return {"path": value} if isinstance(value, str) else value

    @field_validator("hub")
    @classmethod
    def _repo_id(cls, value: str | None) -> str | None:
        if value is not None and not re.fullmatch(r"[\w.-]+/[\w.-]+", value):
            raise ValueError(f"{value!r} is not a Hub repository id: give owner/name (e.g. owl-owl/POVBench)")
        return value

    @model_validator(mode="after")
    def _exactly_one(self) -> DatasetSpec:
        if self.revision is not None and self.hub is None:
            raise ValueError("dataset.revision needs dataset.hub (the Hub repository it is a revision of)")
        if self.download is not None and self.hub is None:
            raise ValueError("dataset.download needs dataset.hub (it bounds fetching that repository)")
        if self.revision is not None:
            from povagent.dataset.hub_checks import HubValueError, check_revision

            try:
                check_revision(self.revision, "dataset.revision")
            except HubValueError as exc:
                raise ValueError(str(exc)) from None
        if self.hub is not None:
            # a path beside hub is the local copy a run resolved it to (see config.yaml)
            if self.generate is not None:
                raise ValueError("give exactly one of dataset.path, dataset.generate or dataset.hub")
            return self
        if (self.path is None) == (self.generate is None):
            raise ValueError("give exactly one of dataset.path, dataset.generate or dataset.hub")
        return self

    @property
    def root(self) -> Path:
        """The dataset folder (the generator's ``out`` for generated datasets; the fetched
        release for ``hub``, once :func:`povagent.dataset.hub.resolve_hub_dataset` ran)."""
        if self.path is not None:
            return self.path
        if self.generate is not None:
            return self.generate.out
        from povagent.errors import DatasetError

        raise DatasetError(
            f"dataset.hub {self.hub}: not fetched yet (call povagent.dataset.hub.resolve_hub_dataset on the "
            f"pipeline first, or fetch it with `povagent download {self.hub}` and give dataset.path)"
        )


_CONDITION_NAMES = {"inferred": "a", "stated": "b", "given": "c"}


class InstanceFilter(_Strict):
    """Which instances a run covers; ``None`` means all."""

    conditions: list[Condition] | None = None
    directions: list[Direction] | None = None
    houses: list[str] | None = None
    sample: int | None = Field(None, ge=1)
    seed: int = 0
    limit: int | None = Field(None, ge=1)

    @field_validator("conditions", mode="before")
    @classmethod
    def _condition_names(cls, value: Any) -> Any:
        if isinstance(value, str):
            value = [value]
        if isinstance(value, list):
            return [_CONDITION_NAMES.get(v.lower(), v.lower()) if isinstance(v, str) else v for v in value]
        return value

    @field_validator("directions", mode="before")
    @classmethod
    def _direction_names(cls, value: Any) -> Any:
        if isinstance(value, str):
            value = [value]
        if isinstance(value, list):
            return [v.lower() if isinstance(v, str) else v for v in value]
        return value




class CacheSpec(_Strict):
    """The response cache: on by default at ``<output>/cache.sqlite``."""

    enabled: bool = True
    path: Path | None = None

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, value: Any) -> Any:
        if isinstance(value, bool):
            return {"enabled": value}
        if isinstance(value, str):
            return {"path": value}
        return value

    @field_validator("path")
    @classmethod
    def _a_file(cls, value: Path | None) -> Path | None:
        if value is not None and value.is_dir():
            raise ValueError("names a folder; the cache is one file (e.g. runs/cache.sqlite)")
        return value


#: Where derived images are written for ``file``/``http`` transport when the pipeline does not
#: say (under the run folder).
DEFAULT_CACHE_DIR = "image-cache"


class ImagesSpec(_Strict):
    """The run's image store, and how images travel to the model.

    ``transport``: ``inline`` (default; base64 data URLs inside the request, as every provider
    takes), ``file`` (``file://`` URLs of the dataset's own files, for a model server on this
    machine, e.g. vLLM with ``--allowed-local-media-path``) or ``http`` (URLs of a read-only
    static server this run starts at ``bind``; ``public_url`` is how the model server reaches
    it, by default ``http://<bind>``). ``cache_dir``: where images without a file of their own
    (frames with markers drawn) are written for ``file``/``http``; default
    ``<output>/image-cache``. Requests, the cache and rows name images by hash whatever the
    transport, so changing it never changes results or resuming.
    """

    max_mb: int = Field(256, ge=1)
    transport: Literal["inline", "file", "http"] = "inline"
    bind: str | None = None
    public_url: str | None = None
    cache_dir: Path | None = None

    @field_validator("bind")
    @classmethod
    def _bind_is_host_port(cls, value: str | None) -> str | None:
        if value is not None:
            parse_bind(value)  # a ValueError names what is wrong
        return value

    @field_validator("public_url")
    @classmethod
    def _public_url_is_http(cls, value: str | None) -> str | None:
        if value is not None and not re.match(r"^https?://[^/\s]+", value):
            raise ValueError(f"public_url {value!r} must be an http:// or https:// URL with a host, e.g. http://gpu-box:8765")
        return value

    @model_validator(mode="after")
    def _options_fit_the_transport(self) -> ImagesSpec:
        if self.transport != "http" and (self.bind is not None or self.public_url is not None):
            raise ValueError(f"bind and public_url apply to transport: http (transport is {self.transport})")
        if self.transport == "inline" and self.cache_dir is not None:
            raise ValueError("cache_dir applies to transport: file or http (inline sends images inside requests)")
        if self.transport == "http":
            if self.bind is None:
                raise ValueError("transport: http needs bind: host:port to serve images at, e.g. bind: 127.0.0.1:8765")
            host, _ = parse_bind(self.bind)
            if host in ("0.0.0.0", "::", "*") and self.public_url is None:
                raise ValueError(
                    f"bind {self.bind} listens on every interface: give public_url, the address the model server "
                    f"reaches this machine at (e.g. http://my-host:{parse_bind(self.bind)[1]})"
                )
        return self

    def cache_folder(self, output: Path) -> Path:
        """Where derived images are written for ``file``/``http`` transport."""
        return self.cache_dir if self.cache_dir is not None else Path(output) / DEFAULT_CACHE_DIR


class PipelineConfig(_Strict):
    """One pipeline: a dataset, a model, a strategy, a parser, scorers, and how to run them."""

    plugins: list[str] = Field(default_factory=list)
    dataset: DatasetSpec
    instances: InstanceFilter = Field(default_factory=InstanceFilter)
    model: str | None = None
    backend: ComponentSpec | None = None
    strategy: ComponentSpec = Field(default_factory=lambda: ComponentSpec(name="basic"))
    parser: ComponentSpec | None = None
    scorers: list[ComponentSpec] = Field(default_factory=lambda: [ComponentSpec(name="official")])
    runs: int | list[int] = 1
    concurrency: int = Field(16, ge=1, le=MAX_CONCURRENCY)
    retry: RetryPolicy = Field(default_factory=RetryPolicy)
    #: seconds one request may take (finite and bounded: no config may make a run wait forever)
    timeout: float = Field(120.0, gt=0, le=MAX_WAIT_S, allow_inf_nan=False)
    #: consecutive infra_error rows that stop the run (a circuit breaker); 0 never stops
    stop_after_failures: int = Field(10, ge=0)
    cache: CacheSpec = Field(default_factory=CacheSpec)
    images: ImagesSpec = Field(default_factory=ImagesSpec)
    output: Path

    @field_validator("runs")
    @classmethod
    def _runs(cls, value: int | list[int]) -> int | list[int]:
        if isinstance(value, int) and value < 1:
            raise ValueError("runs must be at least 1")
        if isinstance(value, int) and value > MAX_RUNS:
            raise ValueError(f"at most {MAX_RUNS} repeats (got {value}); the paper averages 3")
        if isinstance(value, list):
            if not value or any(r < 0 for r in value) or len(set(value)) != len(value):
                raise ValueError("a list of runs must hold distinct run indices >= 0")
            if len(value) > MAX_RUNS:
                raise ValueError(f"at most {MAX_RUNS} run indices (got {len(value)})")
        return value

    @field_validator("output")
    @classmethod
    def _output_is_a_folder(cls, value: Path) -> Path:
        return _a_folder_path(value)

    @model_validator(mode="after")
    def _one_backend(self) -> PipelineConfig:
        if self.model is not None and self.backend is not None:
            raise ValueError("give either model: (a model profile) or backend:, not both")
        if self.model is None and self.backend is None:
            raise ValueError("a backend is required: backend: {name: ..., options: {...}} or model: <profile name>")
        return self

    @property
    def run_indices(self) -> list[int]:
        """The run indices this pipeline covers."""
        return list(range(self.runs)) if isinstance(self.runs, int) else sorted(self.runs)

    def cache_path(self) -> Path | None:
        """Where the response cache lives, or ``None`` when disabled."""
        if not self.cache.enabled:
            return None
        return self.cache.path if self.cache.path is not None else self.output / "cache.sqlite"

    def config_hash(self) -> str:
        """Hash of what determines a row's content (backend, strategy, parser, scorers).

        Resuming into a folder whose rows were made by a different pipeline is refused by
        comparing this. Where and how fast it runs (output, concurrency, retries) is left out.
        """
        keep = {k: v for k, v in self.model_dump(mode="json").items() if k in ("model", "backend", "strategy", "parser", "scorers")}
        blob = json.dumps(keep, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def resolved_dict(self) -> dict[str, Any]:
        """JSON-able dict of the config as run (written to the run folder's ``config.yaml``)."""
        return self.model_dump(mode="json")


class SweepAxes(_Strict):
    """Lists to take the cartesian product of; a missing axis keeps the base's value."""

    model: list[str] | None = None
    backend: list[ComponentSpec] | None = None
    strategy: list[ComponentSpec] | None = None
    parser: list[ComponentSpec] | None = None
    conditions: list[Condition] | None = None
    runs: list[int] | None = None

    @field_validator("conditions", mode="before")
    @classmethod
    def _condition_names(cls, value: Any) -> Any:
        return InstanceFilter._condition_names(value)

    @field_validator("runs")
    @classmethod
    def _run_indices(cls, value: list[int] | None) -> list[int] | None:
        if value is not None and any(r < 0 for r in value):
            raise ValueError("run indices must be >= 0")
        if value is not None and len(value) > MAX_RUNS:
            raise ValueError(f"at most {MAX_RUNS} run indices (got {len(value)})")
        return value


class SweepConfig(_Strict):
    """A sweep: a base pipeline expanded over axes (and named overrides) into cells.

    ::

        base: pipeline_center.yaml   # path relative to this file, or an inline pipeline mapping
        output: runs/baselines       # one folder per cell under it, plus sweep.json
        axes:                        # cartesian product; each value overrides the base
          backend: [center, random, oracle]
          strategy: [basic, spatial-cot]
          conditions: [a, b, c]      # one cell per condition
          runs: [0, 1, 2]            # one cell per run index
        overrides:                   # named partial pipelines, one more axis (optional)
          short-answers: {strategy: {name: basic, options: {max_tokens: 64}}}
        cache: runs/cache.sqlite     # shared by every cell (default <output>/cache.sqlite)
        cluster: local:4             # optional: each cell a task on Dask (or tcp://HOST:8786);
                                     # --cluster overrides it (docs/cluster.md)
    """

    base: str | dict[str, Any]
    output: Path
    axes: SweepAxes = Field(default_factory=SweepAxes)
    overrides: dict[str, dict[str, Any]] = Field(default_factory=dict)
    cache: CacheSpec = Field(default_factory=CacheSpec)
    cluster: str | None = None

    @field_validator("cluster")
    @classmethod
    def _cluster_spec(cls, value: str | None) -> str | None:
        if value is not None:
            try:
                parse_cluster_spec(value)
            except ClusterError as exc:
                raise ValueError(str(exc).replace("--cluster ", "", 1)) from None
        return value

    @field_validator("output")
    @classmethod
    def _output_is_a_folder(cls, value: Path) -> Path:
        return _a_folder_path(value)


# -- YAML with line numbers ---------------------------------------------------------------------
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
                section = _dotted(loc) if loc else "the top level"
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
                    raise ConfigError(f"{where}: alias *{_cut(anchor)} refers to its own anchor (a recursive alias)")
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
    return ConfigError(f"{where}: not valid YAML: {_cut(problem)}")


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
        size = p.stat().st_size
        if size > MAX_CONFIG_BYTES:
            raise ConfigError(
                f"{p}: {size / 1048576:.1f} MiB; a config is at most {MAX_CONFIG_BYTES // 1048576} MiB (is this the right file?)"
            )
        raw = p.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{p}: file not found") from None
    except OSError as exc:
        raise ConfigError(f"{p}: cannot be read: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not UTF-8 text (byte {exc.start} is 0x{raw[exc.start]:02x}); a config is a YAML text file saved as UTF-8") from None
    return parse_yaml(text, str(p))


# -- validation errors --------------------------------------------------------------------------
def _models_in(annotation: Any) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    if get_origin(annotation) is not None or isinstance(annotation, type(Union[int, str])):  # noqa: UP007 -- the runtime class of typing.Union objects, not an annotation
        for arg in get_args(annotation):
            found.extend(_models_in(arg))
    return found


def _model_at(model: type[BaseModel], loc: Loc) -> type[BaseModel] | None:
    for part in loc:
        if isinstance(part, int):
            continue
        info = model.model_fields.get(part)
        if info is None:
            return None
        nested = _models_in(info.annotation)
        if not nested:
            return None
        model = nested[0]
    return model


def _clean_loc(loc: Loc) -> Loc:
    # pydantic inserts validator tags (e.g. 'function-before[...]') into locations; drop them.
    return tuple(p for p in loc if isinstance(p, int) or not ("[" in p or p in ("str", "int", "list[int]")))


def _dotted(loc: Loc) -> str:
    out = ""
    for p in loc:
        out += f"[{p}]" if isinstance(p, int) else (f".{_cut(str(p))}" if out else _cut(str(p)))
    return out or "(top level)"


_QUOTED = re.compile(r"'([^']*)'")


def validation_message(exc: ValidationError, model: type[BaseModel], source: ConfigSource, prefix: Loc = ()) -> str:
    """One line per pydantic error: ``file, line N: field: message (did you mean ...?)``."""
    out: list[str] = []
    for err in exc.errors():
        loc = prefix + _clean_loc(tuple(err["loc"]))
        where = source.where(loc)
        if err["type"] == "extra_forbidden":
            parent = _model_at(model, _clean_loc(tuple(err["loc"]))[:-1])
            allowed = list(parent.model_fields) if parent else []
            bad = loc[-1]
            section = _dotted(loc[:-1]) if loc[:-1] else "the top level"
            out.append(f"{where}: unknown key {shown(bad)} in {section}{did_you_mean(_cut(str(bad)), allowed)}; allowed: {', '.join(allowed)}")
        elif err["type"] == "missing":
            out.append(f"{where}: {_dotted(loc)}: required key is missing")
        else:
            msg = err["msg"].removeprefix("Value error, ")
            if err["type"] == "enum":
                expected = err.get("ctx", {}).get("expected", "")
                choices = _QUOTED.findall(expected)
                msg = f"{shown(err['input'])} is not one of {expected}{did_you_mean(_cut(str(err['input'])), choices)}"
            out.append(f"{where}: {_dotted(loc)}: {msg}")
    return "\n".join(out)


def _validate(model: type[BaseModel], data: Any, source: ConfigSource, what: str) -> Any:
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source.file}: a {what} must be a YAML mapping (key: value), got {type(data).__name__}")
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"invalid {what}:\n{validation_message(exc, model, source)}") from None


# -- plugin names -------------------------------------------------------------------------------
def check_plugin_names(config: PipelineConfig, host: PluginHost, source: ConfigSource, prefix: Loc = ()) -> None:
    """Every plugin name in ``config`` must be registered; errors name the line and a near name."""
    problems: list[str] = []

    def check(kind: str, name: str, loc: Loc) -> None:
        known = host.names(kind)
        if name not in known:
            problems.append(f"{source.where(prefix + loc)}: {_dotted(loc)}: {unknown_name_message(kind, _cut(name), known)}")

    if config.model is not None:
        check("profile", config.model, ("model",))
    if config.backend is not None:
        check("backend", config.backend.name, ("backend", "name") if ("backend", "name") in source.lines else ("backend",))
        check_profile_option(config.backend, host, source, prefix, problems)
        check_env_options(config.backend.options, ("backend", "options"), source, prefix, problems)
    check("strategy", config.strategy.name, ("strategy", "name") if ("strategy", "name") in source.lines else ("strategy",))
    if config.parser is not None:
        check("parser", config.parser.name, ("parser", "name") if ("parser", "name") in source.lines else ("parser",))
    for i, scorer in enumerate(config.scorers):
        check("scorer", scorer.name, ("scorers", i))
    if config.dataset.generate is not None:
        loc = ("dataset", "generate", "judge")
        check("judge", config.dataset.generate.judge.name, loc + ("name",) if loc + ("name",) in source.lines else loc)
    if problems:
        raise ConfigError("invalid pipeline:\n" + "\n".join(problems))


def check_env_options(options: Any, loc: Loc, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """Every ``*_env`` option (``api_key_env``, also inside router deployments) must name an
    environment variable; a key pasted there is refused at its line and never repeated."""
    redactor = Redactor()
    stack: list[tuple[Loc, Any]] = [(loc, options)]
    while stack:
        here, value = stack.pop()
        if isinstance(value, Mapping):
            for k, v in value.items():
                if isinstance(k, str) and k.lower().endswith("_env") and v is not None:
                    if not (isinstance(v, str) and redactor.plausible_variable_name(v)):
                        problems.append(f"{source.where(prefix + here + (k,))}: {_dotted(here + (k,))}: {ENV_NAME_WANTED}")
                else:
                    stack.append((here + (k,), v))
        elif isinstance(value, list):
            stack.extend((here + (i,), v) for i, v in enumerate(value))


def check_profile_option(backend: ComponentSpec, host: PluginHost, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """A near miss of a model profile as the litellm backend's ``model`` option gets the same
    "did you mean" as under ``model:`` (a bare name far from every profile is a litellm model)."""
    model = backend.options.get("model")
    if backend.name != "litellm" or not isinstance(model, str):
        return
    known = host.names("profile")
    if near_profile(model, known) is not None:
        loc = ("backend", "options", "model")
        problems.append(f"{source.where(prefix + loc)}: {_dotted(loc)}: {unknown_name_message('profile', _cut(model), known)}")


def resolve_components(config: PipelineConfig, host: PluginHost) -> PipelineConfig:
    """Fill in what a ``model:`` profile implies: the backend (litellm with that model) and,
    when no parser is given, the profile's default parser (``json`` otherwise). A profile named
    as the litellm backend's ``model`` option (how a vLLM profile gets its ``api_base``) brings
    its parser and strategy defaults the same way."""
    backend, parser, strategy = config.backend, config.parser, config.strategy
    profile = None
    if config.model is not None:
        profile = host.profile(config.model)
        # The litellm backend resolves a profile name given as its model (and applies the
        # profile's backend options itself).
        backend = ComponentSpec(name=getattr(profile, "backend", None) or "litellm", options={"model": config.model})
    elif backend is not None and backend.name == "litellm" and backend.options.get("model") in host.names("profile"):
        profile = host.profile(backend.options["model"])
    if profile is not None:
        if parser is None:
            default = getattr(profile, "default_parser", None) or getattr(profile, "parser", None)
            if isinstance(default, str):
                parser = ComponentSpec(name=default)
        defaults = getattr(profile, "strategy_options", None)
        if isinstance(defaults, Mapping) and defaults:
            strategy = strategy.model_copy(update={"options": {**defaults, **strategy.options}})
    if parser is None:
        parser = ComponentSpec(name="json")
    return config.model_copy(update={"backend": backend, "parser": parser, "strategy": strategy})


def _host_for(plugins: list[str], source: ConfigSource, host: PluginHost | None) -> PluginHost:
    try:
        h = get_plugin_host(plugins) if host is None else host
        if host is not None:
            for mod in plugins:  # an explicit host still gets the config's modules
                if not h.pm.has_plugin(mod):
                    from povagent.plugins import _import_module_or_file

                    h.add_plugin(_import_module_or_file(mod), name=mod, source=f"config plugin {mod}")
        return h
    except PluginError as exc:
        raise ConfigError(f"{source.where(('plugins',))}: {exc}") from None
    except Exception as exc:
        raise ConfigError(f"{source.where(('plugins',))}: plugin failed to load: {type(exc).__name__}: {exc}") from None


# -- pipelines ----------------------------------------------------------------------------------
#: Top-level keys an override replaces whole: options of one plugin never leak into another's.
REPLACED_WHOLE = frozenset({"model", "backend", "strategy", "parser", "scorers"})


def deep_merge(base: Mapping[str, Any], override: Mapping[str, Any], replace: frozenset[str] = frozenset()) -> dict[str, Any]:
    """``base`` with ``override`` merged in (nested mappings merged, everything else replaced;
    keys in ``replace`` are replaced whole)."""
    out = copy.deepcopy(dict(base))
    for k, v in override.items():
        if k not in replace and isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def pipeline_from_source(
    source: ConfigSource,
    *,
    overrides: Mapping[str, Any] | None = None,
    host: PluginHost | None = None,
    prefix: Loc = (),
) -> PipelineConfig:
    """Validate a parsed pipeline document, check its plugin names, and resolve its defaults."""
    data = source.data
    if overrides:
        if not isinstance(data, Mapping):
            raise ConfigError(f"{source.file}: a pipeline must be a YAML mapping (key: value)")
        data = deep_merge(data, overrides, REPLACED_WHOLE)
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source.file}: a pipeline must be a YAML mapping (key: value), got {type(data).__name__}")
    try:
        config = PipelineConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"invalid pipeline:\n{validation_message(exc, PipelineConfig, source, prefix)}") from None
    config = config.model_copy(update={"plugins": checked_plugins(config.plugins, source, prefix)})
    h = _host_for(config.plugins, source, host)
    check_plugin_names(config, h, source, prefix)
    return resolve_components(config, h)


def checked_plugins(plugins: list[str], source: ConfigSource, prefix: Loc = ()) -> list[str]:
    """``plugins`` as the rule of :mod:`povagent.config.plugin_rule` allows them: ``.py`` paths
    resolved inside the YAML file's folder (not the working directory, so the same file loads
    the same plugin wherever the command runs, as a pipeline or as a sweep's base), dotted names
    only from installed packages. A refused entry is a one-line :class:`ConfigError`; nothing is
    imported here. A mapping given from Python (``<pipeline mapping>``) is the caller's own code
    and keeps its entries as they are."""
    folder = source.plugin_folder()
    if folder is None or not plugins:
        return plugins
    return allowed_plugins(plugins, folder, [source.where(prefix + ("plugins", i)) for i in range(len(plugins))])


def load_pipeline(path: str | Path, *, overrides: Mapping[str, Any] | None = None, host: PluginHost | None = None) -> PipelineConfig:
    """Read, validate and resolve a pipeline YAML; any problem is a :class:`ConfigError` that
    names the file, the line and the nearest valid name."""
    return pipeline_from_source(read_yaml(path), overrides=overrides, host=host)


def dump_pipeline(config: PipelineConfig, redactor: Redactor | None = None) -> str:
    """The resolved pipeline as YAML (what a run folder's ``config.yaml`` holds).

    Secrets are redacted (secret-named options, key-shaped strings, the values of ``*_API_KEY``
    variables): a run folder is shared and committed, a secret must never reach it.
    """
    return yaml.safe_dump((redactor or Redactor()).value(config.resolved_dict()), sort_keys=False)


# -- sweeps -------------------------------------------------------------------------------------
def load_sweep(path: str | Path) -> tuple[SweepConfig, ConfigSource, ConfigSource]:
    """Read a sweep YAML and its base pipeline: ``(sweep, sweep source, base source)``."""
    source = read_yaml(path)
    sweep = _validate(SweepConfig, source.data, source, "sweep")
    if isinstance(sweep.base, str):
        base_path = Path(sweep.base)
        if not base_path.is_absolute():
            base_path = Path(path).parent / base_path
        base = read_yaml(base_path)
    else:
        base = ConfigSource(source.file, sweep.base, {k[1:]: v for k, v in source.lines.items() if k[:1] == ("base",)})
    return sweep, source, base
