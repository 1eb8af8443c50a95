"""The run-wide image store: each image read and encoded once, content-addressed, bounded in memory."""

from __future__ import annotations

import base64
import hashlib
import io

from PIL import Image, ImageDraw

from povagent.exchange.images import ImageStore


def png(path, colour, size=(16, 16)):
    Image.new("RGB", size, colour).save(path, format="PNG")
    return path


def test_a_file_is_read_once_however_often_it_is_added(tmp_path):
    store = ImageStore()
    path = png(tmp_path / "a.png", (255, 0, 0))
    first = store.add_file(path)
    again = store.add_file(str(path))
    assert again == first and store.stats.file_reads == 1


def test_an_image_is_named_by_the_hash_of_its_bytes(tmp_path):
    path = png(tmp_path / "a.png", (0, 255, 0), size=(20, 10))
    info = ImageStore().add_file(path)
    assert info.image_hash == hashlib.sha256(path.read_bytes()).hexdigest()
    assert (info.width, info.height, info.media_type) == (20, 10, "image/png")


def test_identical_files_at_two_paths_are_one_image(tmp_path):
    store = ImageStore()
    a = png(tmp_path / "a.png", (1, 2, 3))
    b = tmp_path / "copy.png"
    b.write_bytes(a.read_bytes())
    assert store.add_file(a).image_hash == store.add_file(b).image_hash
    store.data_url(store.add_file(a).image_hash)
    store.data_url(store.add_file(b).image_hash)
    assert store.stats.base64_encodes == 1


def test_data_url_is_encoded_once_and_carries_the_file_bytes(tmp_path):
    store = ImageStore()
    path = png(tmp_path / "a.png", (9, 9, 9))
    h = store.add_file(path).image_hash
    url = store.data_url(h)
    assert store.data_url(h) is url and store.stats.base64_encodes == 1
    prefix = "data:image/png;base64,"
    assert url.startswith(prefix) and base64.b64decode(url[len(prefix):]) == path.read_bytes()


def test_the_memory_bound_evicts_and_an_evicted_image_is_rebuilt_from_its_file(tmp_path):
    paths = [png(tmp_path / f"{i}.png", (i * 40, 0, 0), size=(64, 64)) for i in range(4)]
    one = len(paths[0].read_bytes())
    store = ImageStore(max_bytes=2 * one + one // 2)  # room for two images' bytes
    hashes = [store.add_file(p).image_hash for p in paths]
    assert store._cached_bytes <= store.max_bytes
    assert store.stats.file_reads == 4 and store.stats.rebuilds == 0
    assert store.encoded_bytes(hashes[0]) == paths[0].read_bytes()  # evicted: read again
    assert store.stats.rebuilds == 1 and store.stats.file_reads == 5
    assert store._cached_bytes <= store.max_bytes


def test_a_released_file_loses_its_bytes_and_a_later_use_rebuilds_them(tmp_path):
    store = ImageStore()
    path = png(tmp_path / "a.png", (10, 20, 30), size=(32, 32))
    store.hold_files([path])
    h = store.add_file(path).image_hash
    url = store.data_url(h)
    assert store.cached_bytes == len(path.read_bytes()) + len(url)
    assert store.release_files([path]) == len(path.read_bytes()) + len(url)
    assert store.cached_bytes == 0 and h in store and store.knows_file(path)
    assert store.data_url(h) == url  # rebuilt from the file, and counted
    assert store.stats.rebuilds == 1 and store.stats.file_reads == 2 and store.stats.base64_encodes == 2


def test_a_file_held_twice_stays_until_both_holders_release_it(tmp_path):
    store = ImageStore()
    path = png(tmp_path / "a.png", (1, 1, 1))
    store.hold_files([path])
    store.hold_files([path])
    h = store.add_file(path).image_hash
    store.data_url(h)
    assert store.release_files([path]) == 0 and store.cached_bytes > 0
    assert store.release_files([path]) > 0 and store.cached_bytes == 0
    assert store.release_files([path]) == 0  # an extra release is harmless


def test_a_released_file_whose_bytes_a_held_file_shares_is_kept(tmp_path):
    store = ImageStore()
    a = png(tmp_path / "a.png", (5, 6, 7))
    b = tmp_path / "b.png"
    b.write_bytes(a.read_bytes())
    store.hold_files([a, b])
    h = store.add_file(a).image_hash
    assert store.add_file(b).image_hash == h
    store.data_url(h)
    assert store.release_files([a]) == 0 and store.cached_bytes > 0  # b still needs the same image
    assert store.release_files([b]) > 0 and store.cached_bytes == 0


def test_a_derived_image_is_drawn_once_per_recipe(tmp_path):
    store = ImageStore()
    src = store.add_file(png(tmp_path / "a.png", (200, 200, 200), size=(32, 32))).image_hash
    calls = []

    def dot_at(cx, cy):
        def draw(im):
            calls.append((cx, cy))
            ImageDraw.Draw(im).ellipse((cx - 3, cy - 3, cx + 3, cy + 3), fill=(255, 0, 0))
            return im

        return draw

    first = store.derive(src, "dot@15,15", dot_at(15, 15))
    assert store.derive(src, "dot@15,15", dot_at(15, 15)) == first and calls == [(15, 15)]
    other = store.derive(src, "dot@5,5", dot_at(5, 5))
    assert other.image_hash != first.image_hash and calls == [(15, 15), (5, 5)]
    with Image.open(io.BytesIO(store.encoded_bytes(first.image_hash))) as im:
        assert im.convert("RGB").getpixel((15, 15)) == (255, 0, 0)


def _released(tmp_path):
    """A store that read ``a.png`` and let it go (a house done in one cell of a sweep)."""
    store = ImageStore()
    path = png(tmp_path / "a.png", (10, 20, 30), size=(32, 32))
    store.hold_files([path])
    h = store.add_file(path).image_hash
    store.release_files([path])
    return store, path, h


def test_a_released_frame_swapped_for_a_symlink_is_an_error_naming_it_not_another_image(tmp_path):
    import os

    import pytest

    from povagent.errors import DatasetError

    store, path, h = _released(tmp_path)
    other = png(tmp_path / "elsewhere.png", (200, 0, 0), size=(32, 32))
    path.unlink()
    os.symlink(other, path)
    with pytest.raises(DatasetError, match=r"a\.png: image changed since it was first read"):
        store.data_url(h)


def test_a_released_frame_rewritten_in_place_is_an_error_naming_it(tmp_path):
    import pytest

    from povagent.errors import DatasetError

    store, path, _ = _released(tmp_path)
    png(path, (0, 0, 255), size=(32, 32))
    with pytest.raises(DatasetError, match=r"a\.png: image changed"):
        store.load_file(path)


def test_a_released_frame_replaced_by_a_pipe_is_refused_at_once_not_waited_for(tmp_path):
    import os

    import pytest

    from povagent.errors import DatasetError

    store, path, h = _released(tmp_path)
    path.unlink()
    os.mkfifo(path)  # nobody writes to it: an ordinary open would wait for good
    with pytest.raises(DatasetError, match=r"a\.png: .*not a regular file"):
        store.encoded_bytes(h)


def test_a_released_frame_left_as_it_was_is_read_again(tmp_path):
    store, path, h = _released(tmp_path)
    assert store.encoded_bytes(h) == path.read_bytes() and store.stats.rebuilds == 1
