"""Which reader reads a dataset: the one choice every command makes the same way.

Every reader is a registered dataset format (:class:`~povagent.dataset.formats.DatasetFormat`,
``register_dataset_formats``). A ``format`` (``dataset.format``) names one: an external set's
file (``viewspatial``, ``mindcube``, ``3dsrbench``, or any a plugin registers), read by its
reader. With none, the folder is looked at: each format that can tell its folders apart
(:attr:`~povagent.dataset.formats.DatasetFormat.detect`) is asked in turn, a folder holding
``realworld.json`` being a real-world set and any other folder, a POVBench release or a
generated set, read by the release loader. ``run``, ``rescore``, ``show-prompt`` and the report
all open a set through :func:`open_evaluation_set`, so a set one of them reads is never one
another refuses ("no house folders ... is this a POVBench dataset?" for the shipped real-world
demo). This module must not generate or fetch a set (see :func:`povagent.run.pending.prepare_dataset`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from povagent.dataset.formats import DatasetFormat, FormatRead, registered_format, registered_formats
from povagent.dataset.set_interface import EvaluationSet
from povagent.errors import DatasetError

if TYPE_CHECKING:
    from povagent.plugins import PluginHost


def open_evaluation_set(
    root: str | Path,
    *,
    strict: bool = False,
    check_images: bool = True,
    format: str | None = None,
    images: str | Path | None = None,
    options: Mapping[str, Any] | None = None,
    plugins: Sequence[str] = (),
    host: PluginHost | None = None,
) -> EvaluationSet:
    """The set at ``root``, read by the reader of its format.

    ``strict`` and ``check_images`` are the release loader's (a real-world set is checked
    whole as it is read, and its frames are read to letterbox them; an external set's images
    are checked as it is read). ``format`` (``dataset.format``) makes ``root`` an external
    set's file, read in that format, its image paths relative to ``images`` (default: the
    file's folder), with the format's own ``options`` (``dataset.options``). ``plugins`` are
    the pipeline's ``plugins:`` (a format one of them registers is found), or ``host`` the
    plugins already loaded (a run folder's ``plugins:`` are never imported: ``rescore`` passes
    its command line's).
    """
    root = Path(root)
    dataset_format = format_of(root, format, plugins, host)
    request = FormatRead(root, images=None if images is None else Path(images), strict=strict, check_images=check_images, options=dict(options or {}))
    return dataset_format.read(request)


def format_of(root: Path, format: str | None, plugins: Sequence[str] = (), host: PluginHost | None = None) -> DatasetFormat:
    """The registered format ``format``, or, with none, the first format whose ``detect``
    claims ``root`` (in ``detect_order``). :class:`DatasetError` names an unknown format."""
    if host is None:
        from povagent.plugins import get_plugin_host

        host = get_plugin_host(plugins)
    if format is not None:
        if format not in host.names("format"):
            from povagent.plugins import unknown_name_message

            raise DatasetError(f"{root}: {unknown_name_message('format', format, host.names('format'))}")
        return registered_format(host, format)
    for found in detecting_formats(host):
        if found.detect is not None and found.detect(root):
            return found
    raise DatasetError(f"{root}: no registered dataset format reads this folder; name one as dataset.format")


def detecting_formats(host: PluginHost) -> list[DatasetFormat]:
    """The formats a folder with no ``dataset.format`` may be, in the order they are asked."""
    found = [f for f in registered_formats(host).values() if f.detect is not None]
    return sorted(found, key=lambda f: (f.detect_order, f.key))
