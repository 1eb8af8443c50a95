"""Write a ROS 2 bag of a generated house's tour: what a robot driving through it would record.

    python examples/ros/write_bag.py --out tour_bag                 # generate one house, sqlite3 bag
    python examples/ros/write_bag.py --out tour_bag --storage mcap --dataset DIR

The bag holds /camera/image_raw (rgb8), /camera/camera_info, /tf (map -> base_link, one per
frame, at the frame's stamp) and /tf_static (base_link -> camera_color_optical_frame). The map is
z-up (REP 103); the house's AI2-THOR poses are converted on the way (povagent.ros.house_tour).
Next to the bag, truth.json holds the command, the anchor and furniture boxes in the map and the
ground-truth 3D target, so a replay can be checked (and simulated: see play_to_node.py).

Replay it through the node's code path with any pipeline:

    povagent ros-replay tour_bag --command "$(python -c 'import json;print(json.load(open("tour_bag.truth.json"))["sentence"])')" --pipeline P.yaml
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path


def write(out: Path, dataset: Path | None, storage: str) -> Path:
    """Write the bag and its truth file; returns the truth file's path."""
    from povagent.dataset.loader import load_dataset
    from povagent.ros.house_tour import house_tour, well_seen_instance
    from povagent.ros.tour_bag import write_tour_bag

    with tempfile.TemporaryDirectory(prefix="ros_tour_") as scratch:
        if dataset is None:
            from povagent.generate import generate_dataset

            dataset = Path(scratch) / "POVBench"
            generate_dataset(dataset, houses=1, seed=0, frames=12, jobs=1, progress=False)
        found = well_seen_instance(load_dataset(dataset))
        if found is None:
            raise SystemExit(f"error: no well-seen Inferred instance in {dataset}")
        tour = house_tour(*found)
        write_tour_bag(tour, out, storage="mcap" if storage == "mcap" else "sqlite3")
    t = tour.truth
    truth = out.with_name(out.name + ".truth.json")
    truth.write_text(json.dumps({
        "sentence": t.sentence, "target": t.target, "anchor": t.anchor, "observer": t.observer, "direction": t.direction,
        "surface": t.surface, "objects": {k: [lo.tolist(), hi.tolist()] for k, (lo, hi) in t.objects.items()},
    }, indent=1))
    return truth


def main(argv: list[str] | None = None) -> int:
    """Write the bag; print where it and its truth file are."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, type=Path, help="the bag folder to create (must not exist)")
    ap.add_argument("--dataset", type=Path, help="a POVBench-layout dataset (default: generate one house)")
    ap.add_argument("--storage", choices=("sqlite3", "mcap"), default="sqlite3", help="rosbag2 storage")
    args = ap.parse_args(argv)
    if args.out.exists():
        print(f"error: {args.out} exists already", file=sys.stderr)
        return 1
    truth = write(args.out, args.dataset, args.storage)
    print(f"bag:   {args.out}")
    print(f"truth: {truth}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
