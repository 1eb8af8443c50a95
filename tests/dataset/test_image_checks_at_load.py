"""Images are checked when the dataset loads, once per file, and reported by file.

A truncated PNG, or an image whose size is not its camera's, used to be sent and scored (the
prompt then told the model the wrong size). Loading now checks each image's header, size and
completeness once (off the request path) and refuses what fails: a bad observer view drops its
pair, a bad exploration frame its house (A/B frame indices must not shift). Image errors name
the file, never ``<_io.BytesIO ...>``.
"""

from __future__ import annotations

import pytest
from PIL import Image

from povagent.dataset.loader import load_dataset
from povagent.dataset.validate import validate_dataset
from povagent.errors import DatasetError
from povagent.exchange.images import ImageStore

HOUSE = "train_house_00001"  # pair 7 (two directions), frames frame_000 and frame_001
FRAME = "exploration_images/frame_001.png"
OBSERVER = "img_from_observer/pair_7.png"


def house_path(root, rel):
    return root / "artifacts" / HOUSE / rel


def truncate(path, keep=0.6):
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)])


def flip_a_byte_in_the_image_data(path):
    data = bytearray(path.read_bytes())
    at = data.index(b"IDAT") + 8
    data[at] ^= 0xFF
    path.write_bytes(bytes(data))


def resize(path, size):
    Image.new("RGB", size, (90, 90, 90)).save(path)


def problems_for(problems, file, field):
    return [p for p in problems if p.file.endswith(f"{HOUSE}/{file}") and p.json_path == field]


@pytest.mark.parametrize(
    "damage, words",
    [
        (truncate, "truncated"),
        (flip_a_byte_in_the_image_data, "corrupt"),
        (lambda p: p.write_text("not an image at all"), "not an image"),
        (lambda p: resize(p, (256, 256)), "is 256x256 but its camera is 512x512"),
    ],
    ids=["truncated", "corrupt", "not an image", "wrong size"],
)
def test_a_bad_exploration_frame_refuses_its_house_naming_the_file(dataset_copy, damage, words):
    damage(house_path(dataset_copy, FRAME))
    ds = load_dataset(dataset_copy)
    assert HOUSE not in ds.houses and "train_house_00000" in ds.houses
    found = problems_for(ds.problems, "exploration_log.json", "$[1].image_path")
    assert found and words in found[0].message and FRAME in found[0].message, ds.problems


@pytest.mark.parametrize(
    "damage, words",
    [(truncate, "truncated"), (lambda p: resize(p, (640, 480)), "is 640x480 but its camera is 512x512")],
    ids=["truncated", "wrong size"],
)
def test_a_bad_observer_view_refuses_its_pair_naming_the_file(dataset_copy, damage, words):
    damage(house_path(dataset_copy, OBSERVER))
    ds = load_dataset(dataset_copy)
    assert "7" not in ds.houses.get(HOUSE, None).pairs if HOUSE in ds.houses else True
    assert not [i for i in ds.instances() if i.house_id == HOUSE]
    found = problems_for(ds.problems, f"{HOUSE}.json", "$[0].rgb_path")
    assert found and words in found[0].message and OBSERVER in found[0].message, ds.problems


def test_an_observer_view_takes_its_size_from_its_own_camera(dataset_copy, editor):
    editor.edit(HOUSE, lambda pairs: pairs[0]["camera"].update(screen_width=640, screen_height=480))
    resize(house_path(dataset_copy, OBSERVER), (640, 480))
    ds = load_dataset(dataset_copy)
    assert not ds.problems and ds.instance(f"{HOUSE}/7/front/c").frame_size == (640, 480)


def test_strict_loading_stops_at_a_bad_image(dataset_copy):
    truncate(house_path(dataset_copy, FRAME))
    with pytest.raises(DatasetError, match=r"frame_001.png"):
        load_dataset(dataset_copy, strict=True)


def test_validate_says_truncated_too(dataset_copy):
    truncate(house_path(dataset_copy, FRAME))
    found = problems_for(validate_dataset(dataset_copy), "exploration_log.json", "$[1].image_path")
    assert found and "truncated" in found[0].message


def test_each_image_is_checked_once_per_process(dataset_copy, opened_files):
    load_dataset(dataset_copy)
    first = [f for f in opened_files if f.endswith(".png")]
    assert sorted(set(first)) == sorted(first)  # no file opened twice in one load
    opened_files.clear()
    load_dataset(dataset_copy)
    assert not [f for f in opened_files if f.endswith(".png")]


def test_a_file_changed_after_its_check_is_checked_again(dataset_copy):
    assert HOUSE in load_dataset(dataset_copy).houses
    truncate(house_path(dataset_copy, FRAME))
    assert HOUSE not in load_dataset(dataset_copy).houses


def test_the_image_store_names_the_file_it_cannot_read(tmp_path):
    bad = tmp_path / "frame_009.png"
    bad.write_text("not an image")
    with pytest.raises(DatasetError) as err:
        ImageStore().add_file(bad)
    assert str(bad) in str(err.value) and "BytesIO" not in str(err.value)


def test_the_image_store_names_a_truncated_file(tmp_path):
    path = tmp_path / "frame_010.png"
    Image.effect_noise((64, 64), 40).convert("RGB").save(path)
    truncate(path, 0.5)
    with pytest.raises(DatasetError, match=r"frame_010.png"):
        ImageStore().add_file(path)


def test_an_image_that_passes_the_load_check_but_does_not_decode_names_its_file(tmp_path):
    # A PNG whose checksums hold but whose compressed pixels are garbage (made on purpose):
    # drawing on it fails with the file's name, not Pillow's <_io.BytesIO ...>.
    import struct
    import zlib

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    path = tmp_path / "frame_011.png"
    header = struct.pack(">IIBBBBB", 8, 8, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", b"garbage!") + chunk(b"IEND", b""))
    store = ImageStore()
    info = store.add_file(path)
    with pytest.raises(DatasetError) as err:
        store.open(info.image_hash)
    assert "frame_011.png" in str(err.value) and "BytesIO" not in str(err.value)
