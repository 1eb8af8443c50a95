"""The pipeline schema: pydantic models of every key a pipeline config may hold, with their defaults
and bounds (a sweep's own keys are :mod:`povagent.config.sweep_models`).

What a config may ask for is bounded here: repeats (:data:`MAX_RUNS`), retries and waits
(:class:`~povagent.config.retry_policy.RetryPolicy`), the request timeout (finite, at most
:data:`MAX_WAIT_S`) and concurrency (:data:`MAX_CONCURRENCY`). Unknown keys are errors (a typo
is never silently ignored) and numbers are finite.

The models are data, at the bottom of the config: besides the data models they hold
(the retry policy, the Hub download bounds, conditions and directions) they use only pure
parsers of single values (``host:port``). This module must not read files
(that is :mod:`povagent.config.yaml_reader`), load plugins or check their names
(:mod:`povagent.config.plugin_checks`), or import the engine, the runner or the image
transports that act on these values.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Any, Literal, Mapping

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_serializer, model_validator

from povagent.config.addresses import parse_bind
from povagent.config.retry_policy import RetryPolicy
from povagent.dataset.hub_limits import DownloadLimits
from povagent.dataset.release_models import Condition, Direction

#: Most repeats a pipeline may ask for (``runs: N`` or a list of N indices); the paper uses 3.
MAX_RUNS = 100
#: Longest ``label:`` a pipeline may give its system (it heads table rows and plot legends).
MAX_LABEL_CHARS = 120
#: Longest request timeout, in seconds.
MAX_WAIT_S = 3600.0
#: Most requests in flight.
MAX_CONCURRENCY = 1024


class StrictModel(BaseModel):
    """The base of every config model: unknown keys are errors (a typo must never be silently ignored); numbers are finite
    (``.inf`` is a wait that never ends)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


def a_folder_path(value: Path) -> Path:
    """``value`` may become a folder: neither it nor any existing parent is a file."""
    for p in (value, *value.parents):
        if p.exists():
            if not p.is_dir():
                where = "names" if p == value else f"is under {p}, which is"
                raise ValueError(f"{where} an existing file, not a folder: choose a folder path for the run's files")
            break
    return value


class ComponentSpec(StrictModel):
    """A plugin by name with its options (a bare string is the name with no options)."""

    name: str = Field(min_length=1)
    options: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="before")
    @classmethod
    def _bare_name(cls, value: Any) -> Any:
        return {"name": value} if isinstance(value, str) else value


class GenerateSpec(StrictModel):
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


class DatasetSpec(StrictModel):
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
    #: The format of an external multiple-choice set whose file ``path`` names (see
    #: :mod:`povagent.dataset.choice_sets`), and the folder its image paths are relative to and
    #: confined to (default: the file's). ``None``: a POVBench-layout folder.
    format: str | None = Field(None, min_length=1, max_length=64)
    images: Path | None = None
    #: The format's own options (``{frames: 16}``; :attr:`~povagent.dataset.formats.DatasetFormat.option_names`).
    options: dict[str, Any] | None = None

    @model_validator(mode="before")
    @classmethod
    def _bare_path(cls, value: Any) -> Any:
        return {"path": value} if isinstance(value, str) else value

    @model_serializer(mode="wrap")
    def _no_format_for_a_folder(self, handler: Any) -> dict[str, Any]:
        # a POVBench run's config.yaml stays byte for byte what it was before formats existed
        return {k: v for k, v in handler(self).items() if k not in ("format", "images", "options") or v is not None}

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
        if self.format is not None and (self.path is None or self.generate is not None or self.hub is not None):
            raise ValueError(f"dataset.format {self.format} needs dataset.path: the set's file, downloaded yourself")
        if self.options is not None and self.format is None:
            raise ValueError("dataset.options needs dataset.format (they are that format's reader's options)")
        if self.images is not None and self.format is None:
            raise ValueError("dataset.images needs dataset.format (it is where an external set's images are)")
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
        release for ``hub``, once :func:`povagent.config.pipeline.resolve_hub_dataset` ran)."""
        if self.path is not None:
            return self.path
        if self.generate is not None:
            return self.generate.out
        from povagent.errors import DatasetError

        raise DatasetError(
            f"dataset.hub {self.hub}: not fetched yet (call povagent.config.pipeline.resolve_hub_dataset on the "
            f"pipeline first, or fetch it with `povagent download {self.hub}` and give dataset.path)"
        )


_CONDITION_NAMES = {"inferred": "a", "stated": "b", "given": "c"}


class InstanceFilter(StrictModel):
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




class CacheSpec(StrictModel):
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


class ImagesSpec(StrictModel):
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


#: The tasks a pipeline may ask of a dataset's instances: POVBench's point task, and the paper's
#: future-work tasks on generated houses (:mod:`povagent.tasks`).
TASK_NAMES = ("point", "relation", "multi-hop", "navigate")
#: The answers each task may be asked in, its default first (``navigate``: a walk ending in
#: ``arrived()``, which the ``navigate`` strategy records).
TaskAnswer = Literal["point", "choice", "walk"]
TASK_ANSWERS: dict[str, tuple[TaskAnswer, ...]] = {
    "point": ("point",),
    "relation": ("choice",),
    "multi-hop": ("point", "choice"),
    "navigate": ("walk",),
}
#: The strategy and scorers a pipeline of a task gets when it names none (the point task's are
#: the fields' own defaults).
TASK_DEFAULTS: dict[str, tuple[str, tuple[str, ...]]] = {"navigate": ("navigate", ("navigate",))}


class TaskSpec(StrictModel):
    """What a pipeline asks of each instance: ``task: relation`` or ``task: {name: multi-hop,
    answer: choice}``. ``answer`` defaults to the task's first (multi-hop: ``point``, the
    official metric)."""

    name: Literal["point", "relation", "multi-hop", "navigate"] = "point"
    answer: TaskAnswer | None = None

    @model_validator(mode="before")
    @classmethod
    def _bare_name(cls, value: Any) -> Any:
        value = {"name": value} if isinstance(value, str) else value
        name = value.get("name", "point") if isinstance(value, dict) else "point"
        if name not in TASK_NAMES:
            raise ValueError(f"unknown task {str(name)[:80]!r}: one of {', '.join(TASK_NAMES)}")
        return value

    @model_validator(mode="after")
    def _answer_fits(self) -> TaskSpec:
        allowed = TASK_ANSWERS[self.name]
        if self.answer is None:
            self.answer = allowed[0]
        elif self.answer not in allowed:
            raise ValueError(f"task {self.name} is answered as {' or '.join(allowed)}, not {self.answer}")
        return self

    @property
    def is_point_task(self) -> bool:
        """POVBench's own task (the default): the config hash and ``config.yaml`` leave it out."""
        return self.name == "point"


class PipelineConfig(StrictModel):
    """One pipeline: a dataset, a model, a strategy, a parser, scorers, and how to run them."""

    plugins: list[str] = Field(default_factory=list)
    dataset: DatasetSpec
    instances: InstanceFilter = Field(default_factory=InstanceFilter)
    #: What each instance asks (:class:`TaskSpec`); in the config hash unless it is the point task.
    task: TaskSpec = Field(default_factory=TaskSpec)
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
    #: The system's name in reports (``base``, ``fine-tuned step 120``); default: its model.
    #: Presentation only, so not in the config hash. Runs of one ``label`` pool into one system.
    label: str | None = Field(None, min_length=1, max_length=MAX_LABEL_CHARS, pattern=r"\S")

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
        return a_folder_path(value)

    @model_validator(mode="after")
    def _one_backend(self) -> PipelineConfig:
        if self.model is not None and self.backend is not None:
            raise ValueError("give either model: (a model profile) or backend:, not both")
        if self.model is None and self.backend is None:
            raise ValueError("a backend is required: backend: {name: ..., options: {...}} or model: <profile name>")
        return self

    @model_validator(mode="after")
    def _task_defaults(self) -> PipelineConfig:
        """A task's own strategy and scorers where the pipeline names none (``task: navigate``)."""
        defaults = TASK_DEFAULTS.get(self.task.name)
        if defaults is not None:
            strategy, scorers = defaults
            if "strategy" not in self.model_fields_set:
                self.strategy = ComponentSpec(name=strategy)
            if "scorers" not in self.model_fields_set:
                self.scorers = [ComponentSpec(name=name) for name in scorers]
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

    def config_hash(self, strategy_identity: Mapping[str, Any] | None = None) -> str:
        """Hash of what determines a row's content (backend, strategy, parser, scorers).

        Resuming into a folder whose rows were made by a different pipeline is refused by
        comparing this. Where and how fast it runs (output, concurrency, retries) is left out.
        ``strategy_identity`` is what the strategy says decides its rows beyond the YAML (the
        active mode's tools offered); empty or ``None`` leaves the hash as the YAML's alone.
        """
        keep = {k: v for k, v in self.model_dump(mode="json").items() if k in ("model", "backend", "strategy", "parser", "scorers")}
        if not self.task.is_point_task:  # rows of different tasks never share a folder
            keep["task"] = self.task.model_dump(mode="json")
        if strategy_identity:
            keep["strategy_identity"] = dict(strategy_identity)
        blob = json.dumps(keep, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def resolved_dict(self) -> dict[str, Any]:
        """JSON-able dict of the config as run (written to the run folder's ``config.yaml``); the
        point task, the default, is left out (a point run's file is as it always was)."""
        return self.model_dump(mode="json", exclude={"task"} if self.task.is_point_task else None)
