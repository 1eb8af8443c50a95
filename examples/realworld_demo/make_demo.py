"""Re-create the demo real-world set in this folder: four drawn "house-tour" frames and commands.

The frames are drawn, not photographed (so they can ship with the repository), in two sizes
(1280x720 landscape and 480x640 portrait) to exercise letterboxing; the commands follow the
paper's three conditions. Run ``python examples/realworld_demo/make_demo.py`` to rebuild; the
output is deterministic.
"""

from __future__ import annotations

from pathlib import Path

from PIL import Image, ImageDraw

from povagent.dataset.realworld_set import Command, Mark, RealWorldHouse, RealWorldSet, Scenario, write_realworld

HERE = Path(__file__).resolve().parent

FLOOR, WALL, OUTLINE = (168, 132, 96), (214, 208, 196), (40, 40, 40)


def frame(size: tuple[int, int], items: list[tuple[str, tuple[int, int, int, int], tuple[int, int, int]]]) -> Image.Image:
    """A flat "room": wall, floor, and labelled boxes standing for furniture."""
    w, h = size
    im = Image.new("RGB", size, WALL)
    d = ImageDraw.Draw(im)
    d.rectangle([0, int(h * 0.55), w, h], fill=FLOOR)
    for label, box, colour in items:
        d.rectangle(box, fill=colour, outline=OUTLINE, width=3)
        d.text((box[0] + 6, box[1] + 4), label, fill=(255, 255, 255))
    return im


FRAMES = {
    "house_1/frame_00.jpg": ((1280, 720), [
        ("sofa", (120, 380, 620, 560), (70, 90, 140)),
        ("coffee table", (680, 470, 940, 560), (120, 80, 50)),
        ("tv", (1000, 220, 1220, 360), (20, 20, 20)),
    ]),
    "house_1/frame_01.jpg": ((1280, 720), [
        ("counter", (80, 330, 900, 470), (230, 230, 230)),
        ("kettle", (400, 270, 470, 330), (180, 40, 40)),
        ("fridge", (960, 120, 1180, 600), (200, 200, 210)),
    ]),
    "house_1/frame_02.jpg": ((1280, 720), [
        ("bed", (200, 380, 860, 620), (150, 170, 200)),
        ("side table", (900, 430, 1040, 560), (120, 80, 50)),
        ("lamp", (940, 300, 1000, 430), (240, 220, 120)),
    ]),
    "house_1/frame_03.jpg": ((480, 640), [
        ("desk", (60, 360, 420, 460), (120, 80, 50)),
        ("chair", (180, 420, 300, 600), (60, 60, 60)),
    ]),
}


def build() -> RealWorldSet:
    """The set's index (GT marked in original-frame pixels)."""
    kitchen = Scenario(
        id="kitchen",
        observer_view="house_1/frame_01.jpg",
        commands=[
            Command(condition="a", direction="right",
                    sentence="While I was making tea, I left my phone to the right of the kettle.",
                    gt=[Mark(frame="house_1/frame_01.jpg", point=(540, 310))]),
            Command(condition="b", direction="right",
                    sentence="While I was making tea at the counter, I left my phone to the right of the kettle.",
                    gt=[Mark(frame="house_1/frame_01.jpg", point=(540, 310))]),
            Command(condition="c", direction="right", sentence="My phone is to the right of the kettle.",
                    gt=[Mark(box=(490, 270, 600, 340))]),
        ],
    )
    bedroom = Scenario(
        id="bedroom",
        observer_view="house_1/frame_02.jpg",
        commands=[
            Command(condition="a", direction="up",
                    sentence="While I was reading in bed, I put my glasses on top of the side table.",
                    gt=[Mark(frame="house_1/frame_02.jpg", region=[(900, 410), (1040, 410), (1040, 450), (900, 450)])]),
            Command(condition="c", direction="up", sentence="My glasses are on top of the side table.",
                    gt=[Mark(point=(970, 425), radius_px=60)]),
        ],
    )
    study = Scenario(
        id="study",
        observer_view="house_1/frame_03.jpg",
        commands=[
            Command(condition="a", direction="front",
                    sentence="While I was working, I dropped a pen in front of the chair.",
                    gt=[Mark(frame="house_1/frame_03.jpg", point=(240, 615))]),
        ],
    )
    house = RealWorldHouse(id="house_1", frames=list(FRAMES), scenarios=[kitchen, bedroom, study])
    return RealWorldSet(description="A drawn demo set: one house, four frames, three scenarios.", houses=[house])


def main() -> None:
    """Write the frames and realworld.json next to this script."""
    for rel, (size, items) in FRAMES.items():
        path = HERE / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        frame(size, items).save(path, quality=80)
    print(write_realworld(build(), HERE))


if __name__ == "__main__":
    main()
