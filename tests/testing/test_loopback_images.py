"""The loopback server fetching image URLs as a vLLM server does (povagent/testing/loopback_server.py).

``data:`` URLs are decoded, ``file://`` URLs read only beneath ``local_media_root``,
``http://`` URLs downloaded from 127.0.0.1 only; every image's bytes and SHA-256 are recorded,
and an image that cannot be fetched is answered 400.
"""

from __future__ import annotations

import base64
import hashlib
import json
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from povagent.exchange.image_server import StaticImageServer
from povagent.testing.loopback_server import LoopbackServer

pytestmark = pytest.mark.timeout(20)

PNG_A = b"\x89PNG\r\n\x1a\n" + b"A" * 300
PNG_B = b"\x89PNG\r\n\x1a\n" + b"B" * 300


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def post_images(server: LoopbackServer, urls: list[str]) -> tuple[int, dict]:
    content = [{"type": "text", "text": "Where?"}] + [{"type": "image_url", "image_url": {"url": u}} for u in urls]
    body = {"model": "m", "messages": [{"role": "user", "content": content}]}
    req = urllib.request.Request(server.url + "/chat/completions", data=json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=10) as resp:
            return resp.status, json.loads(resp.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


@pytest.fixture
def media(tmp_path) -> Path:
    root = tmp_path / "media"
    root.mkdir()
    (root / "a.png").write_bytes(PNG_A)
    (root / "b.png").write_bytes(PNG_B)
    return root


def test_data_urls_are_decoded_and_recorded(media):
    url = "data:image/png;base64," + base64.b64encode(PNG_A).decode()
    with LoopbackServer(fetch_images=True) as server:
        status, _ = post_images(server, [url])
    assert status == 200
    (image,) = server.requests[0].images
    assert (image.scheme, image.data, image.sha256, image.size) == ("data", PNG_A, sha(PNG_A), len(PNG_A))


def test_file_urls_beneath_the_media_root_are_read_in_order(media):
    with LoopbackServer(fetch_images=True, local_media_root=media) as server:
        status, _ = post_images(server, [(media / "b.png").as_uri(), (media / "a.png").as_uri()])
    assert status == 200
    assert [i.data for i in server.requests[0].images] == [PNG_B, PNG_A]
    assert server.images_fetched == 2


def test_file_urls_outside_the_media_root_are_answered_400(media, tmp_path):
    secret = tmp_path / "secret.png"
    secret.write_bytes(b"secret")
    with LoopbackServer(fetch_images=True, local_media_root=media) as server:
        status, doc = post_images(server, [(media / "a.png").as_uri(), secret.as_uri()])
    assert status == 400
    assert "image 1" in doc["error"]["message"] and "outside" in doc["error"]["message"]
    assert server.image_failures == 1
    assert server.request_count == 0  # never answered as a completion


def test_file_urls_need_a_media_root(media):
    with LoopbackServer(fetch_images=True) as server:
        status, doc = post_images(server, [(media / "a.png").as_uri()])
    assert status == 400 and "not allowed" in doc["error"]["message"]


def test_a_symlink_out_of_the_media_root_is_answered_400(media, tmp_path):
    secret = tmp_path / "secret.png"
    secret.write_bytes(b"secret")
    (media / "link.png").symlink_to(secret)
    with LoopbackServer(fetch_images=True, local_media_root=media) as server:
        status, _ = post_images(server, [(media / "link.png").as_uri()])
    assert status == 400


def test_a_symlink_that_stays_beneath_the_media_root_is_read_as_a_hub_cache_snapshot_is(media):
    blobs = media / "blobs"
    blobs.mkdir()
    (blobs / "0123abcd").write_bytes(PNG_B)
    (media / "snapshot.png").symlink_to(blobs / "0123abcd")
    with LoopbackServer(fetch_images=True, local_media_root=media) as server:
        status, _ = post_images(server, [(media / "snapshot.png").as_uri()])
    assert status == 200 and server.requests[0].images[0].data == PNG_B


def test_dot_dot_out_of_the_media_root_is_answered_400(media, tmp_path):
    (tmp_path / "secret.png").write_bytes(b"secret")
    with LoopbackServer(fetch_images=True, local_media_root=media) as server:
        status, doc = post_images(server, [f"file://{media}/../secret.png"])
    assert status == 400 and "outside" in doc["error"]["message"]


def test_a_fifo_or_a_folder_is_refused_at_once_never_waited_on(media):
    import os

    os.mkfifo(media / "pipe.png")
    (media / "folder.png").mkdir()
    with LoopbackServer(fetch_images=True, local_media_root=media) as server:
        fifo_status, fifo_doc = post_images(server, [(media / "pipe.png").as_uri()])
        dir_status, dir_doc = post_images(server, [(media / "folder.png").as_uri()])
    assert fifo_status == 400 and "not a regular file" in fifo_doc["error"]["message"]
    assert dir_status == 400 and "folder.png" in dir_doc["error"]["message"]


def test_http_urls_are_downloaded_from_the_static_server(media):
    with StaticImageServer([media]) as images, LoopbackServer(fetch_images=True) as server:
        url = images.publish(media / "a.png", sha(PNG_A))
        status, _ = post_images(server, [url])
    assert status == 200
    (image,) = server.requests[0].images
    assert (image.scheme, image.data) == ("http", PNG_A)


def test_http_urls_beyond_this_machine_are_never_fetched():
    with LoopbackServer(fetch_images=True) as server:
        status, doc = post_images(server, ["http://example.com/a.png"])
    assert status == 400 and "only 127.0.0.1" in doc["error"]["message"]


def test_an_image_the_check_rejects_is_answered_400(media):
    expected = {sha(PNG_A)}
    with LoopbackServer(fetch_images=True, local_media_root=media,
                        image_check=lambda i: None if i.sha256 in expected else "unexpected image") as server:
        assert post_images(server, [(media / "a.png").as_uri()])[0] == 200
        status, doc = post_images(server, [(media / "b.png").as_uri()])
    assert status == 400 and "unexpected image" in doc["error"]["message"]


def test_bad_base64_is_answered_400():
    with LoopbackServer(fetch_images=True) as server:
        status, _ = post_images(server, ["data:image/png;base64,@@@not-base64@@@"])
    assert status == 400


def test_digests_without_bytes_when_told_not_to_keep_them(media):
    with LoopbackServer(fetch_images=True, local_media_root=media, keep_image_bytes=False) as server:
        post_images(server, [(media / "a.png").as_uri()])
    (image,) = server.requests[0].images
    assert (image.data, image.sha256) == (None, sha(PNG_A))


def test_without_fetch_images_urls_are_only_recorded(media):
    with LoopbackServer() as server:
        status, _ = post_images(server, [(media / "a.png").as_uri()])
    assert status == 200
    assert server.requests[0].images == []
    assert server.requests[0].image_urls() == [(media / "a.png").as_uri()]
