"""The release records of an instance's house, for offline backends that answer from them.

The ``simulated`` perception simulator and the ``planted`` behaviour simulator answer from the
dataset's own records (pairs, exploration log). They find the house folder the instance's frames
are in (the release layout's ``artifacts/<house>/``), or use a ``dataset`` folder given as an
option, and read each house once.
"""

from __future__ import annotations

import threading
from pathlib import Path

from povagent.dataset.instances import Instance
from povagent.dataset.loader import House, load_house
from povagent.interfaces import PermanentBackendError


class HouseRecords:
    """Reads and keeps the house records of instances; ``backend`` names the backend in errors."""

    def __init__(self, backend: str, dataset: Path | None = None) -> None:
        self.backend = backend
        self.dataset = dataset
        self._houses: dict[Path, House] = {}
        self._lock = threading.Lock()

    def house_of(self, instance: Instance) -> House:
        """The house records of ``instance`` (read once per house folder)."""
        folder = self.house_folder(instance)
        with self._lock:
            house = self._houses.get(folder)
        if house is None:
            problems: list = []
            house = load_house(folder, folder.parent.parent, problems)
            if house is None:
                listing = "; ".join(str(p) for p in problems[:3])
                raise PermanentBackendError(f"{self.backend} backend: cannot read the records of {folder}: {listing}")
            with self._lock:
                self._houses[folder] = house
        return house

    def house_folder(self, instance: Instance) -> Path:
        """The release-layout house folder of ``instance``."""
        if self.dataset is not None:
            folder = self.dataset / "artifacts" / instance.house_id
            if folder.is_dir():
                return folder
            raise PermanentBackendError(f"{self.backend} backend: option 'dataset': {folder} is not a house folder")
        for frame in instance.frames:
            for parent in Path(frame.file).parents:
                if parent.name == instance.house_id and (parent / f"{instance.house_id}.json").is_file():
                    return parent
        raise PermanentBackendError(
            f"{self.backend} backend: the frames of {instance.id} are not inside a release-layout house folder; "
            "set the backend option 'dataset' to the dataset folder"
        )
