"""The POVBench release layout: typed models, loading, validation and evaluation instances."""

from povagent.dataset.instances import Frame, Instance, instance_id, row_key
from povagent.dataset.loader import Dataset, House, load_dataset
from povagent.dataset.release_models import CONDITIONS, DIRECTIONS, Condition, Direction

__all__ = [
    "CONDITIONS",
    "DIRECTIONS",
    "Condition",
    "Dataset",
    "Direction",
    "Frame",
    "House",
    "Instance",
    "instance_id",
    "load_dataset",
    "row_key",
]
