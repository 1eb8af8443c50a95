"""Loading pipelines and sweeps: read the YAML, validate it, check its plugins, resolve its defaults.

A pipeline YAML (every key but ``dataset``, ``output`` and one of ``backend``/``model`` has a
default)::

    plugins: [my_pkg.my_plugin]          # extra plugin modules: installed dotted names, or .py paths
                                         # inside this file's folder (see docs/explanation/security.md)
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

A config is untrusted input too, and what it may ask for is bounded: what the reader takes
(size, nesting, alias expansion, duplicate keys, UTF-8: :mod:`povagent.config.yaml_reader`) and
what the schema allows (repeats, retries and waits, the request timeout and concurrency:
:mod:`povagent.config.models`); values quoted back in messages are cut short.

The pieces it puts together (the schema, the YAML reader, the validation messages, the plugin
checks, the merging of overrides) are listed in :mod:`povagent.config`; the functions here
are the ones callers use: :func:`load_pipeline`, :func:`pipeline_from_source`,
:func:`dump_pipeline` and :func:`load_sweep`.

This module reads and checks configs; it must not run anything (see :mod:`povagent.run.runner`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import yaml
from pydantic import BaseModel, ValidationError

from povagent.config.models import PipelineConfig
from povagent.config.overrides import REPLACED_WHOLE, deep_merge
from povagent.config.plugin_checks import check_parser_fits, check_plugin_names, check_task_fits, checked_plugins, plugin_host_for, resolve_components
from povagent.config.quoting import Loc
from povagent.config.sweep_models import SweepConfig
from povagent.config.validation_messages import validation_message
from povagent.config.yaml_reader import ConfigSource, read_yaml
from povagent.errors import ConfigError
from povagent.files.redaction import Redactor
from povagent.plugins import PluginHost


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
    h = plugin_host_for(config.plugins, source, host)
    check_plugin_names(config, h, source, prefix)
    resolved = resolve_components(config, h)
    check_parser_fits(resolved, h, source, prefix)
    check_task_fits(resolved, h, source, prefix)
    return resolved


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
def _validate(model: type[BaseModel], data: Any, source: ConfigSource, what: str) -> Any:
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source.file}: a {what} must be a YAML mapping (key: value), got {type(data).__name__}")
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"invalid {what}:\n{validation_message(exc, model, source)}") from None


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


def default_scorers() -> list[str]:
    """The scorers of a pipeline that names none (the config's default): what a run whose
    config names no scorers was scored by."""
    return [s.name for s in PipelineConfig.model_fields["scorers"].get_default(call_default_factory=True)]


def resolve_hub_dataset(config: PipelineConfig, *, progress: bool = True) -> PipelineConfig:
    """Fetch a pipeline's ``dataset: {hub: ...}`` and point ``dataset.path`` at the release root.

    Only the files of the pipeline's ``instances.conditions`` are fetched. The revision is
    pinned to the commit it resolved to, so the run folder's ``config.yaml`` names exactly the
    data the run used (and a resume reads that commit, offline from the cache). Updates
    ``config`` in place (every later reader of ``config.dataset.root`` sees the local folder)
    and returns it; a config without ``hub`` is returned untouched.
    """
    from povagent.dataset.hub import download_release  # huggingface_hub: only when a hub set is named

    spec = config.dataset
    if spec.hub is None:
        return config
    release = download_release(
        spec.hub, revision=spec.revision, conditions=config.instances.conditions, progress=progress, limits=spec.download
    )
    config.dataset = spec.model_copy(update={"path": release.root, "revision": release.commit})
    return config
