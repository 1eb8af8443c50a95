"""Under ``pytest-xdist --dist loadfile``: the folders whose files share an expensive per-process
resource are handed to one worker as one unit.

tests/cluster's files share one running Dask cluster (``shared_dask_cluster``), started when the
first of them runs and stopped when the next test is another folder's. loadfile hands out one file
at a time, sorted by test count, so the folder's five files land far apart in each worker's queue,
with other folders' files between them: the cluster was started once per file (four times a
suite, in both workers), each start a scheduler's and two workers' start-up and imports. As one
unit, one worker runs the folder's files in a row and starts the cluster once.
"""

from __future__ import annotations

from pathlib import Path

import pytest

#: Folders (relative to this one) run by one worker, file after file.
ONE_UNIT_FOLDERS = ("cluster",)


class FolderUnits:
    """A plugin: loadfile's scheduler, with each of :data:`ONE_UNIT_FOLDERS` one work unit."""

    def __init__(self, rootpath: Path) -> None:
        here = Path(__file__).resolve().parent
        self.prefixes = tuple((here / name).relative_to(rootpath).as_posix() + "/" for name in ONE_UNIT_FOLDERS)

    @pytest.hookimpl(tryfirst=True)
    def pytest_xdist_make_scheduler(self, config: pytest.Config, log: object) -> object:
        from xdist.scheduler import LoadFileScheduling

        prefixes = self.prefixes

        class Scheduling(LoadFileScheduling):
            def _split_scope(self, nodeid: str) -> str:
                unit = next((p for p in prefixes if nodeid.startswith(p)), None)
                return unit if unit is not None else super()._split_scope(nodeid)

        return Scheduling(config, log)  # type: ignore[arg-type]


def register(config: pytest.Config) -> None:
    """Install :class:`FolderUnits` when this session distributes files with pytest-xdist (the
    README's ``--dist loadfile``); any other run is left as it is."""
    if hasattr(config, "workerinput"):  # a worker: only the controller schedules
        return
    if not config.pluginmanager.hasplugin("xdist") or getattr(config.option, "dist", "no") != "loadfile":
        return
    try:
        plugin = FolderUnits(config.rootpath.resolve())
    except ValueError:  # these tests outside the rootdir: nodeids name them otherwise
        return
    config.pluginmanager.register(plugin, "povagent-folder-units")
