"""A report on a run whose dataset holds a corrupt image still gets written.

``povagent report`` used to die in the gallery (``PIL.UnidentifiedImageError``) after writing
the tables but before ``report.html``. A bad image now becomes a card that says so, naming the
file; every other card is drawn as usual.
"""

from __future__ import annotations

import json
import re
import shutil

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.dataset.loader import load_dataset
from povagent.report.gallery import build_gallery

HOUSE = "train_house_00000"


@pytest.fixture
def damaged_dataset(tmp_path, mini_root):
    """The fixture dataset with every image of one house damaged (one truncated, the rest not
    images at all): whatever frame a row selected, its card needs a bad image."""
    root = tmp_path / "ds"
    shutil.copytree(mini_root, root)
    images = sorted((root / "artifacts" / HOUSE).glob("*/*.png"))
    for i, path in enumerate(images):
        if i == 0:
            path.write_bytes(path.read_bytes()[:200])
        else:
            path.write_text("this is not a PNG")
    return root


def gallery_entries(html: str) -> list[dict]:
    match = re.search(r'<script type="application/json" id="gallery-data">(.*?)</script>', html, re.S)
    assert match, "no gallery data in the page"
    return json.loads(match.group(1).replace("<\\/", "</").replace("<\\!--", "<!--"))["entries"]


def test_report_is_written_and_a_bad_image_becomes_a_card_that_says_so(run_dir, damaged_dataset, tmp_path):
    out = tmp_path / "r"
    result = CliRunner().invoke(app, ["report", str(run_dir), "--out", str(out), "--bootstrap", "0", "--dataset", str(damaged_dataset)])
    assert result.exit_code == 0, result.output
    page = (out / "report.html").read_text(encoding="utf-8")
    entries = gallery_entries(page)
    bad = [e for e in entries if e["id"].startswith(HOUSE + "/")]
    good = [e for e in entries if not e["id"].startswith(HOUSE + "/")]
    drawn_bad = [e for e in bad if e.get("ie")]
    assert drawn_bad, "no card says its image is bad"
    for e in drawn_bad:
        assert e["img"] is None and re.search(r"(frame_00\d|pair_0)\.png", e["ie"]), e["ie"]
    assert all(e["img"] for e in good if e.get("k") is not None or e["c"] == "c")
    assert "image not drawn" in page  # the card's wording, in the page's script


def test_the_gallery_draws_the_good_images_and_counts_the_bad(mini_root, damaged_dataset, run_dir, tmp_path):
    from povagent.report.collect import collect

    ds = load_dataset(damaged_dataset, check_images=False)
    collection = collect(run_dir)
    entries, stats = build_gallery(collection.observations, collection.systems, ds, tmp_path / "g")
    assert stats.bad_images >= 1 and stats.drawn >= 1
    for e in entries:
        if e.get("ie"):
            assert e["img"] is None
    assert not list((tmp_path / "g" / "images").glob("*.tmp"))


def test_a_run_loaded_for_a_report_keeps_the_house_with_a_bad_image(damaged_dataset):
    # The report draws cards for every row, so it loads without the load-time image check
    # (a run refuses the house; a report says which image failed).
    assert HOUSE in load_dataset(damaged_dataset, check_images=False).houses
    assert HOUSE not in load_dataset(damaged_dataset).houses


def test_a_frame_planted_as_a_pipe_becomes_a_card_that_says_so_not_a_wait(run_dir, tmp_path, mini_root):
    import os

    root = tmp_path / "ds"
    shutil.copytree(mini_root, root)
    for path in sorted((root / "artifacts" / HOUSE).glob("*/*.png")):
        path.unlink()
        os.mkfifo(path)
    out = tmp_path / "r"
    result = CliRunner().invoke(app, ["report", str(run_dir), "--out", str(out), "--bootstrap", "0", "--dataset", str(root)])
    assert result.exit_code == 0, result.output
    bad = [e for e in gallery_entries((out / "report.html").read_text(encoding="utf-8")) if e["id"].startswith(HOUSE + "/") and e.get("ie")]
    assert bad and all("named pipe" in e["ie"] and e["img"] is None for e in bad), bad
