"""Pipeline and sweep YAML: typed models, safe loading, and errors that say where and what.

A pipeline YAML (every key but ``dataset``, ``output`` and one of ``backend``/``model`` has a
default)::

    plugins: [my_pkg.my_plugin]          # extra plugin modules (dotted names or .py paths)
    dataset: {path: data/povbench}       # or {generate: {houses: 3, seed: 0, frames: 30, out: data/gen}}
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
    cache: true                          # true (default: <output>/cache.sqlite), false, or a path
    images: {max_mb: 256}                # memory bound of the run's image store; how images travel:
                                         # transport: inline (base64, default) | file | http
                                         # (http: bind: 127.0.0.1:8765, public_url: http://host:8765)
    output: runs/my-run

Relative paths are relative to the working directory. A typo in a key or a plugin name fails
before any request, naming the file, the line and the nearest valid name.

This module reads and checks configs; it must not run anything (see :mod:`povagent.run.runner`).
"""

from __future__ import annotations

import copy
import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Literal, Mapping, Union, get_args, get_origin

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from povagent.dataset.models import Condition, Direction
from povagent.errors import ConfigError, PluginError
from povagent.exchange.image_server import parse_bind
from povagent.exchange.transport import DEFAULT_CACHE_DIR
from povagent.run.logs import Redactor
from povagent.plugins import PluginHost, did_you_mean, get_plugin_host, unknown_name_message

Loc = tuple[Any, ...]


# -- models -------------------------------------------------------------------------------------
class _Strict(BaseModel):
    """Unknown keys are errors (a typo must never be silently ignored)."""

    model_config = ConfigDict(extra="forbid")


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
    """Where the instances come from: an existing release-layout folder, or a generator spec."""

    path: Path | None = None
    generate: GenerateSpec | None = None
    #: Stop at the first bad house or pair instead of reporting it and going on.
    strict: bool = False

    @model_validator(mode="before")
    @classmethod
    def _bare_path(cls, value: Any) -> Any:
        return {"path": value} if isinstance(value, str) else value

    @model_validator(mode="after")
    def _exactly_one(self) -> "DatasetSpec":
        if (self.path is None) == (self.generate is None):
            raise ValueError("give exactly one of dataset.path or dataset.generate")
        return self

    @property
    def root(self) -> Path:
        """The dataset folder (the generator's ``out`` for generated datasets)."""
        return self.path if self.path is not None else self.generate.out  # type: ignore[union-attr]


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


class RetryPolicy(_Strict):
    """Retries on transient failures: ``attempts`` in all (first try included), exponential
    backoff from ``initial_wait`` to ``max_wait`` seconds; a server's Retry-After wins."""

    attempts: int = Field(5, ge=1)
    initial_wait: float = Field(1.0, ge=0)
    max_wait: float = Field(60.0, ge=0)


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
    def _options_fit_the_transport(self) -> "ImagesSpec":
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
    concurrency: int = Field(16, ge=1)
    retry: RetryPolicy = Field(default_factory=RetryPolicy)
    timeout: float = Field(120.0, gt=0)
    cache: CacheSpec = Field(default_factory=CacheSpec)
    images: ImagesSpec = Field(default_factory=ImagesSpec)
    output: Path

    @field_validator("runs")
    @classmethod
    def _runs(cls, value: int | list[int]) -> int | list[int]:
        if isinstance(value, int) and value < 1:
            raise ValueError("runs must be at least 1")
        if isinstance(value, list):
            if not value or any(r < 0 for r in value) or len(set(value)) != len(value):
                raise ValueError("a list of runs must hold distinct run indices >= 0")
        return value

    @model_validator(mode="after")
    def _one_backend(self) -> "PipelineConfig":
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
    """

    base: str | dict[str, Any]
    output: Path
    axes: SweepAxes = Field(default_factory=SweepAxes)
    overrides: dict[str, dict[str, Any]] = Field(default_factory=dict)
    cache: CacheSpec = Field(default_factory=CacheSpec)


# -- YAML with line numbers ---------------------------------------------------------------------
@dataclass
class ConfigSource:
    """A YAML document: its file name, data, and the line of every key and list item."""

    file: str
    data: Any
    lines: dict[Loc, int] = field(default_factory=dict)

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


def _record_lines(node: yaml.Node, loc: Loc, lines: dict[Loc, int]) -> None:
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            if key is None:
                continue
            lines[loc + (key,)] = key_node.start_mark.line + 1
            _record_lines(value_node, loc + (key,), lines)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            lines[loc + (i,)] = item.start_mark.line + 1
            _record_lines(item, loc + (i,), lines)


def parse_yaml(text: str, file: str) -> ConfigSource:
    """Parse YAML with the safe loader, keeping the line of every key; errors name the line."""
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        data = loader.construct_document(node) if node is not None else None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{file}, line {mark.line + 1}" if mark is not None else file
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError(f"{where}: not valid YAML: {problem}") from None
    finally:
        loader.dispose()
    lines: dict[Loc, int] = {}
    if node is not None:
        _record_lines(node, (), lines)
    return ConfigSource(file, data, lines)


def read_yaml(path: str | Path) -> ConfigSource:
    """Read and parse a YAML file (a missing file is a :class:`ConfigError`)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{p}: file not found") from None
    except OSError as exc:
        raise ConfigError(f"{p}: cannot be read: {exc.strerror or exc}") from None
    return parse_yaml(text, str(p))


# -- validation errors --------------------------------------------------------------------------
def _models_in(annotation: Any) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    if get_origin(annotation) is not None or isinstance(annotation, type(Union[int, str])):
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
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
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
            out.append(f"{where}: unknown key {bad!r} in {section}{did_you_mean(str(bad), allowed)}; allowed: {', '.join(allowed)}")
        elif err["type"] == "missing":
            out.append(f"{where}: {_dotted(loc)}: required key is missing")
        else:
            msg = err["msg"].removeprefix("Value error, ")
            if err["type"] == "enum":
                expected = err.get("ctx", {}).get("expected", "")
                choices = _QUOTED.findall(expected)
                msg = f"{err['input']!r} is not one of {expected}{did_you_mean(str(err['input']), choices)}"
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
            problems.append(f"{source.where(prefix + loc)}: {_dotted(loc)}: {unknown_name_message(kind, name, known)}")

    if config.model is not None:
        check("profile", config.model, ("model",))
    if config.backend is not None:
        check("backend", config.backend.name, ("backend", "name") if ("backend", "name") in source.lines else ("backend",))
    check("strategy", config.strategy.name, ("strategy", "name") if ("strategy", "name") in source.lines else ("strategy",))
    if config.parser is not None:
        check("parser", config.parser.name, ("parser", "name") if ("parser", "name") in source.lines else ("parser",))
    for i, scorer in enumerate(config.scorers):
        check("scorer", scorer.name, ("scorers", i))
    if config.dataset.generate is not None:
        loc = ("dataset", "generate", "judge")
        check("judge", config.dataset.generate.judge.name, loc + ("name",) if loc + ("name",) in source.lines else loc)
    if problems:
        raise ConfigError("unknown plugin name(s):\n" + "\n".join(problems))


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
    h = _host_for(config.plugins, source, host)
    check_plugin_names(config, h, source, prefix)
    return resolve_components(config, h)


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
