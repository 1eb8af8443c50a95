"""The bird's-eye view of a gallery card, drawn from the release's records and seen in Chromium.

The drawing must put each thing where the records say (checked through the page transform),
the gallery must link it from the card's viewer, and a real browser must render it: the GT
target's green dot where the transform puts it, the prediction's red ray, nothing blank.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import yaml
from PIL import Image
from test_report_html import VIEWER_SETTLED, dump, gallery_data, rendered  # the Chromium helpers

from povagent.config.pipeline import load_pipeline
from povagent.dataset.loader import load_dataset
from povagent.report.birds_eye import VIEW_PX, _Frame, birds_eye_svg, prediction_on_floor, scene_for
from povagent.report.build import write_report
from povagent.run.runner import run_pipeline

SVG = "{http://www.w3.org/2000/svg}"



def page_transform(scene):
    """The transform the drawing used, rebuilt from the same points."""
    from povagent.report.birds_eye import FOV_LENGTH_M, _fov_wedge

    pts = [(b.x0, b.z0) for b in scene.objects] + [(b.x1, b.z1) for b in scene.objects]
    pts += [(c.position[0], c.position[2]) for c in (*scene.exploration, scene.observer_camera)]
    pts.append((scene.target[0], scene.target[2]))
    pts += _fov_wedge(scene.selected, FOV_LENGTH_M)
    floor, _ = prediction_on_floor(scene.selected, scene.prediction)
    pts.append((float(floor[0]), float(floor[2])))
    return _Frame(pts)


def a_scene(root, condition="a"):
    dataset = load_dataset(root)
    instance = dataset.instances(conditions=[condition])[0]
    frame = instance.frames[min(3, len(instance.frames) - 1)]
    return scene_for(instance, dataset.houses[instance.house_id], frame.camera, (256.0, 400.0)), instance


@pytest.mark.parametrize("release", ["generated", "hand-made"])
def test_everything_is_drawn_where_the_records_put_it(release, generated_release, mini_root):
    scene, instance = a_scene(generated_release if release == "generated" else mini_root)
    root = ET.fromstring(birds_eye_svg(scene))
    page = page_transform(scene)
    target = root.find(f".//{SVG}circle[@id='target']")
    assert (float(target.get("cx")), float(target.get("cy"))) == pytest.approx(page(instance.target[0], instance.target[2]), abs=0.06)
    apex = root.find(f".//{SVG}polygon[@id='fov']").get("points").split()[0].split(",")
    assert tuple(map(float, apex)) == pytest.approx(page(scene.selected.position[0], scene.selected.position[2]), abs=0.06)
    ray = root.find(f".//{SVG}g[@id='prediction']/{SVG}line")
    floor, met = prediction_on_floor(scene.selected, scene.prediction)
    assert met and (float(ray.get("x2")), float(ray.get("y2"))) == pytest.approx(page(floor[0], floor[2]), abs=0.06)
    rects = root.findall(f".//{SVG}g[@id='objects']/{SVG}rect")
    assert len(rects) == len(scene.objects) >= 2
    assert [r.get("class") for r in rects].count("anchor") == 1 and [r.get("class") for r in rects].count("observer") == 1
    assert len(root.findall(f".//{SVG}g[@id='exploration-cameras']/{SVG}circle")) == len(instance.frames)


def test_the_top_view_keeps_left_and_right(generated_release):
    """A camera facing up the page has its right on the page's right (left-handed, y up)."""
    scene, _ = a_scene(generated_release)
    page = page_transform(scene)
    x0, _ = page(0.0, 0.0)
    x1, _ = page(1.0, 0.0)  # world +x is a yaw-0 camera's right
    _, y0 = page(0.0, 0.0)
    _, y1 = page(0.0, 1.0)  # world +z is its forward: up the page
    assert x1 > x0 and y1 < y0


@pytest.fixture(scope="module")
def simulated_report(generated_release, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("birds-eye")
    path = tmp / "pipeline.yaml"
    house = sorted(p.name for p in (generated_release / "artifacts").iterdir())[0]
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(generated_release)},
        "backend": {"name": "simulated", "options": {"pixel_sigma": 10, "seed": 2}},
        "strategy": "geometric",
        "parser": "json",
        "instances": {"houses": [house], "conditions": ["a"]},
        "output": str(tmp / "run"),
    }))
    run_pipeline(load_pipeline(path))
    return write_report(tmp / "run", tmp / "report", n_boot=0)


def test_an_opened_card_shows_its_scene_from_above_in_chromium(simulated_report, browser):
    entries = gallery_data(simulated_report)["entries"]
    assert all(re.fullmatch(r"[0-9a-f]{64}", e["be"]) for e in entries)
    dom = dump(browser, simulated_report.page, "open=0", until=VIEWER_SETTLED)
    src = re.search(r'<img class="birds-eye" alt="the scene from above" src="(images/[0-9a-f]{64}\.svg)">', dom)
    assert src and (simulated_report.out / src.group(1)).exists()


def test_chromium_renders_the_svg_with_the_target_and_the_ray(simulated_report, tmp_path, generated_release, browser):
    entry = gallery_data(simulated_report)["entries"][0]
    svg = simulated_report.out / "images" / f"{entry['be']}.svg"
    shot = tmp_path / "birds_eye.png"
    rendered(browser, svg.as_uri(), shot=shot, window=(VIEW_PX, VIEW_PX + 56), until=None)  # a drawing: no script to wait for
    assert shot.exists()
    px = np.asarray(Image.open(shot).convert("RGB"), dtype=int)[:VIEW_PX]  # the scene, not the legend
    r, g, b = px[..., 0], px[..., 1], px[..., 2]
    green = np.argwhere((g > 170) & (r < 60) & (b < 130))
    red = (r > 220) & (g < 90) & (b < 90)
    assert len(green) > 20 and red.sum() > 20
    target = ET.parse(svg).getroot().find(f".//{SVG}circle[@id='target']")
    centre = green.mean(axis=0)  # (row, column)
    assert (centre[1], centre[0]) == pytest.approx((float(target.get("cx")), float(target.get("cy"))), abs=3.0)
