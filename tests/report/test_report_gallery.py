"""Gallery drawings (povagent/report/gallery.py): markers where the metric puts them, files named by hash."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from povagent.report.collect import Observation
from povagent.report.gallery import drawing_for, write_answer_chunks
from povagent.report.gallery_drawing import GT_COLOUR, PRED_COLOUR, render
from povagent.scoring.normalized_l2 import score_point


def observation(instance, x: float, y: float, selected: int | None) -> Observation:
    return Observation(
        system="m", run_name="r", run=0, instance_id=instance.id, house_id=instance.house_id, pair_id=instance.pair_id,
        direction=str(instance.direction), condition=str(instance.condition), status="answered", parse_status="ok",
        answered=True, l2=None, l2_strict=None, gt_in_frame=None, gt_behind=None, gt_u=None, gt_v=None,
        selected_image=selected, image_path=None, x=x, y=y, sentence=instance.sentence, raw="{}",
    )


def near(pixel, colour, tol: int = 60) -> bool:
    return all(abs(int(a) - int(b)) <= tol for a, b in zip(pixel, colour))


@pytest.fixture(scope="module")
def given(mini_dataset):
    inst = next(i for i in mini_dataset.instances(conditions=["c"]) if score_point(i, i.frames[0], 0, 0).gt_in_frame)
    return inst


def test_gt_ring_and_predicted_cross_are_drawn_where_the_metric_puts_them(given):
    w, h = given.frame_size
    score = score_point(given, given.frames[0], 40.0, 40.0)
    drawing = drawing_for(observation(given, 40.0, 40.0, None), given)
    gx, gy = score.gt_u * w, score.gt_v * h
    assert drawing.gt == pytest.approx((gx, gy)) and drawing.gt_state == "in"
    im = np.asarray(render(drawing))
    assert near(im[40, 40], PRED_COLOUR)  # the two strokes of the cross meet on the predicted pixel
    assert near(im[int(round(gy)), int(round(gx))], GT_COLOUR)  # the ring's centre dot
    with Image.open(drawing.source) as src:
        original = np.asarray(src.convert("RGB"))
    # away from both markers the frame is untouched: the corner farthest from the GT (the
    # cross sits near the top-left corner, so that one is never chosen)
    corners = [(y, x) for y in (5, h - 6) for x in (5, w - 6) if (y, x) != (5, 5)]
    far = max(corners, key=lambda c: (c[0] - gy) ** 2 + (c[1] - gx) ** 2)
    assert (im[far] == original[far]).all()


def test_gt_behind_the_selected_camera_is_drawn_at_the_centre_where_the_metric_scores_it(mini_dataset):
    behind = [
        (inst, k)
        for inst in mini_dataset.instances(conditions=["a", "b"])
        for k, frame in enumerate(inst.frames)
        if score_point(inst, frame, 0, 0).gt_behind
    ]
    # the fixture is built with one (house 0's frame_001, yaw 180): losing it is drift, not a skip
    assert behind, "tests/fixtures/povbench_mini has no exploration frame looking away from a target"
    inst, k = behind[0]
    d = drawing_for(observation(inst, 10.0, 10.0, k), inst)
    w, h = inst.frame_size
    assert d.gt_state == "behind" and d.gt == (w / 2, h / 2)


def test_no_selected_frame_means_no_drawing(mini_dataset):
    inst = next(iter(mini_dataset.instances(conditions=["a"])))
    assert drawing_for(observation(inst, 10.0, 10.0, None), inst) is None


def test_answer_files_are_named_by_their_content_and_take_the_text_out_of_the_entries(tmp_path):
    entries = [{"id": str(i), "a": f"answer {i}"} for i in range(5)]
    names = write_answer_chunks(entries, tmp_path, chunk=2)
    assert len(names) == 3 and all("a" not in e for e in entries)
    assert entries[3]["ac"] == [1, 1]
    assert '"a":"answer 3"' in (tmp_path / "answers" / f"{names[1]}.js").read_text()
    again = [{"id": str(i), "a": f"answer {i}"} for i in range(5)]
    assert write_answer_chunks(again, tmp_path, chunk=2) == names  # same text, same files
