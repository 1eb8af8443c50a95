"""Child of ``test_bytes_across_cpus.py``: generate one small house and render one view, then
print the SHA-256 of every file and of the view's PNG as JSON. Run as a script in a process
whose CPU features (numpy's dispatch, OpenBLAS's kernel, embree's ISA) the parent chose."""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

from povagent.generate import generate_dataset, house_pipeline
from povagent.generate.frame_png import encode_frame_png
from povagent.generate.house_pipeline import BuiltHouse, build_house
from povagent.geometry.camera import Camera


def main(out: Path) -> None:
    # the view is rendered in the house the generation built (kept when it builds it), not in
    # a second build of the same house: a build is about a second of this child's CPU
    built_here: list[BuiltHouse] = []

    def build_and_keep(seed: int, index: int, shadows: bool = True) -> BuiltHouse:
        built_here.append(build_house(seed, index, shadows))
        return built_here[-1]

    house_pipeline.build_house = build_and_keep
    generate_dataset(out, houses=1, seed=11, frames=3, jobs=1, progress=False)
    digests = {p.relative_to(out).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
               for p in sorted(out.rglob("*")) if p.is_file()}  # fmt: skip
    (built,) = built_here
    room = built.house.plan.rooms[0].rect.center
    view = built.renderer.render(Camera((room[0], 1.5, room[1]), 37.5, 12.0, 90.0, 320, 240))
    digests["<view>"] = hashlib.sha256(encode_frame_png(view.rgb)).hexdigest()
    print(json.dumps(digests, sort_keys=True))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
