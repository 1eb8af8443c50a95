"""Frames by reference (povagent/exchange/transport.py), end to end through the litellm backend.

A 30-frame request goes to the loopback server inline, as ``file://`` URLs and as ``http://``
URLs of the static server; the server fetches every image as a model server would and each
image's bytes must be the store's. Derived images are written once to the cache folder.
"""

from __future__ import annotations

import asyncio
import hashlib
import os
from pathlib import Path

import pytest
from PIL import Image, ImageDraw

from povagent.answers.spec import AnswerSpec, frame_answer_schema
from povagent.errors import ConfigError
from povagent.exchange.image_server import ImageReferenceError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent.exchange.transport import (
    FileTransport,
    HttpTransport,
    InlineTransport,
    image_transport,
    make_transport,
)
from povagent.interfaces import PermanentBackendError
from povagent.testing.loopback_server import LoopbackServer
from povagent.testing.pytest_plugin import write_release
from povagent_plugins.backends.litellm_backend import LiteLLMBackend

pytestmark = pytest.mark.timeout(60)

N_FRAMES = 30


@pytest.fixture(scope="module")
def release(tmp_path_factory) -> Path:
    """One house with 30 distinct 512x512 frames (the paper's shape)."""
    return write_release(tmp_path_factory.mktemp("transport") / "povbench", houses=1, pairs=1, pair_directions=1,
                         frames=N_FRAMES)


@pytest.fixture(scope="module")
def frames(release) -> list[Path]:
    found = sorted(release.glob("artifacts/*/exploration_images/*.png")) or sorted(release.rglob("*.png"))
    assert len(found) >= N_FRAMES
    return found[:N_FRAMES]


def thirty_frame_request(store: ImageStore, frames: list[Path]) -> Request:
    parts: list = []
    for i, path in enumerate(frames):
        parts += [TextPart(f"Image {i}:"), ImagePart(store.add_file(path).image_hash, label=f"Image {i}:")]
    parts.append(TextPart("Sentence: the mug is to the left of the sofa."))
    spec = AnswerSpec(schema=frame_answer_schema(len(frames), 512, 512), n_frames=len(frames), asks_frame=True)
    return Request(messages=(Message("user", tuple(parts)),), answer=spec, generation=GenerationParams(max_tokens=64))


def backend_for(server: LoopbackServer, model: str = "openai/loopback-vlm") -> LiteLLMBackend:
    return LiteLLMBackend(model=model, api_base=server.url, api_key_env="POVAGENT_TEST_KEY", timeout=30)


def send(backend: LiteLLMBackend, request: Request, store: ImageStore):
    async def go():
        try:
            return await backend.complete(request, store)
        finally:
            await backend.aclose()

    return asyncio.run(go())


@pytest.fixture
def api_key(monkeypatch) -> str:
    """A fake API key exported as POVAGENT_TEST_KEY."""
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-transport")
    return "sk-test-transport"


@pytest.fixture
def server(release, api_key):
    with LoopbackServer(reply='{"selected_image": 0, "x": 1, "y": 2}', fetch_images=True,
                        local_media_root=release.parent, max_lifetime_s=50) as s:
        yield s


@pytest.mark.parametrize("transport", ["inline", "file", "http"])
def test_a_thirty_frame_request_arrives_byte_for_byte(transport, server, release, frames, tmp_path):
    store = ImageStore()
    request = thirty_frame_request(store, frames)
    with image_transport(store, make_transport(transport, dataset_root=release, cache_dir=tmp_path / "cache")):
        response = send(backend_for(server), request, store)
    assert response.text.startswith('{"selected_image"')
    (got,) = server.requests
    assert [img.scheme for img in got.images] == [{"inline": "data"}.get(transport, transport)] * N_FRAMES
    assert [img.data for img in got.images] == [p.read_bytes() for p in frames]
    assert [img.sha256 for img in got.images] == request.image_hashes()


def test_hosted_vllm_models_receive_references_untouched(server, release, frames, tmp_path):
    store = ImageStore()
    request = thirty_frame_request(store, frames)
    with image_transport(store, FileTransport(tmp_path / "cache")):
        send(backend_for(server, "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct"), request, store)
    (got,) = server.requests
    assert got.image_urls() == [p.absolute().as_uri() for p in frames]
    assert [img.data for img in got.images] == [p.read_bytes() for p in frames]


def test_file_urls_name_the_datasets_own_files_and_write_nothing(release, frames, tmp_path):
    store = ImageStore()
    h = store.add_file(frames[3]).image_hash
    transport = FileTransport(tmp_path / "cache")
    with image_transport(store, transport):
        assert store.url(h) == frames[3].absolute().as_uri()
    assert transport.written == 0 and not (tmp_path / "cache").exists()


def marked(image: Image.Image) -> Image.Image:
    ImageDraw.Draw(image).ellipse((10, 10, 40, 40), outline=(255, 0, 0), width=3)
    return image


def test_derived_images_are_written_once_to_the_cache_folder_and_referenced(server, release, frames, tmp_path):
    store = ImageStore()
    source = store.add_file(frames[0]).image_hash
    derived = store.derive(source, "marker at (25, 25)", marked).image_hash
    cache = tmp_path / "cache"
    transport = FileTransport(cache)
    with image_transport(store, transport):
        first, again = store.url(derived), store.url(derived)
    written = cache / f"{derived}.png"
    assert first == again == written.as_uri()
    assert transport.written == 1
    assert hashlib.sha256(written.read_bytes()).hexdigest() == derived
    assert [p.name for p in cache.iterdir()] == [written.name]  # no temporary file left behind


def test_a_cached_derived_image_is_not_written_again_by_a_later_run(frames, tmp_path):
    store = ImageStore()
    derived = store.derive(store.add_file(frames[0]).image_hash, "marker", marked).image_hash
    FileTransport(tmp_path / "cache").url(store, derived)
    later = FileTransport(tmp_path / "cache")
    later.url(store, derived)
    assert later.written == 0


def test_derived_images_travel_over_http_too(server, release, frames, tmp_path):
    store = ImageStore()
    source = store.add_file(frames[0]).image_hash
    derived = store.derive(source, "marker", marked).image_hash
    in_memory = store.add_pil(Image.new("RGB", (8, 8), "blue")).image_hash
    parts = (TextPart("Image 0:"), ImagePart(derived), TextPart("Image 1:"), ImagePart(in_memory))
    request = Request(messages=(Message("user", parts),), answer=AnswerSpec(schema=frame_answer_schema(2, 512, 512), n_frames=2))
    with image_transport(store, make_transport("http", dataset_root=release, cache_dir=tmp_path / "cache")):
        send(backend_for(server), request, store)
    (got,) = server.requests
    assert [img.sha256 for img in got.images] == [derived, in_memory]
    assert all(url.startswith("http://127.0.0.1:") for url in got.image_urls())


def test_the_http_transport_stops_its_server_with_the_block(release, tmp_path):
    store = ImageStore()
    transport = make_transport("http", dataset_root=release, cache_dir=tmp_path / "cache")
    assert isinstance(transport, HttpTransport)
    with image_transport(store, transport):
        assert store.transport is transport
    assert store.transport is None
    assert transport.server._server is None


def test_a_frame_outside_the_dataset_is_refused_over_http_as_a_permanent_error(server, release, tmp_path):
    elsewhere = tmp_path / "elsewhere.png"
    Image.new("RGB", (8, 8), "red").save(elsewhere)
    store = ImageStore()
    h = store.add_file(elsewhere).image_hash
    request = Request(messages=(Message("user", (ImagePart(h),)),), answer=AnswerSpec(schema=frame_answer_schema(1, 8, 8)))
    with image_transport(store, make_transport("http", dataset_root=release, cache_dir=tmp_path / "cache")):
        with pytest.raises(ImageReferenceError):
            store.url(h)
        with pytest.raises(PermanentBackendError, match="by reference"):
            send(backend_for(server), request, store)
    assert server.request_count == 0


def test_a_symlinked_frame_pointing_out_of_the_dataset_is_refused_over_http(release, tmp_path):
    secret = tmp_path / "secret.png"
    Image.new("RGB", (8, 8), "green").save(secret)
    link = release / "artifacts" / "sneaky.png"
    os.symlink(secret, link)
    try:
        store = ImageStore()
        h = store.add_file(link).image_hash
        with (
            image_transport(store, make_transport("http", dataset_root=release, cache_dir=tmp_path / "cache")),
            pytest.raises(ImageReferenceError, match="outside"),
        ):
            store.url(h)
    finally:
        link.unlink()


def test_without_a_transport_the_store_sends_data_urls(frames):
    store = ImageStore()
    h = store.add_file(frames[0]).image_hash
    assert store.transport is None
    assert store.url(h) == store.data_url(h)
    assert InlineTransport().url(store, h) == store.data_url(h)


def test_an_http_bind_that_cannot_listen_is_a_config_error(release, tmp_path):
    first = make_transport("http", dataset_root=release, cache_dir=tmp_path / "cache")
    try:
        with pytest.raises(ConfigError, match="bind"):
            make_transport("http", dataset_root=release, cache_dir=tmp_path / "cache",
                           bind=f"127.0.0.1:{first.server.port}")
    finally:
        first.close()


def test_the_loopback_server_refuses_file_urls_outside_its_media_root(release, frames, tmp_path, api_key):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with LoopbackServer(fetch_images=True, local_media_root=elsewhere, max_lifetime_s=30) as s:
        store = ImageStore()
        request = thirty_frame_request(store, frames[:1])
        with image_transport(store, FileTransport(tmp_path / "cache")), pytest.raises(PermanentBackendError, match=r"400|outside"):
            send(backend_for(s), request, store)
        assert s.image_failures == 1 and s.images_fetched == 0


@pytest.fixture
def umask():
    """``umask(mask)`` sets the process umask for the test; the old one is restored after."""
    old = os.umask(0o022)
    os.umask(old)
    yield os.umask
    os.umask(old)


@pytest.mark.parametrize(("mask", "mode"), [(0o022, 0o644), (0o027, 0o640), (0o002, 0o664)])
def test_derived_images_are_written_with_the_permissions_of_ordinary_files(frames, tmp_path, umask, mask, mode):
    store = ImageStore()
    derived = store.derive(store.add_file(frames[0]).image_hash, "marker", marked).image_hash
    umask(mask)
    FileTransport(tmp_path / "cache").url(store, derived)
    assert (tmp_path / "cache" / f"{derived}.png").stat().st_mode & 0o777 == mode


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="switching to another user needs root")
def test_a_model_server_running_as_another_user_reads_a_derived_image(frames, tmp_path_factory, umask):
    import shutil
    import subprocess
    import sys
    import tempfile

    store = ImageStore()
    derived = store.derive(store.add_file(frames[0]).image_hash, "marker", marked).image_hash
    shared = Path(tempfile.mkdtemp(prefix="povagent-shared-"))  # as a run folder others may read
    try:
        shared.chmod(0o755)
        umask(0o022)
        url = FileTransport(shared / "cache").url(store, derived)
        nobody = 65534

        def become_nobody() -> None:
            os.setgid(nobody)
            os.setuid(nobody)

        # the system's Python: the virtual environment may not be readable by that user either
        python = shutil.which("python3", path="/usr/bin:/bin") or sys.executable
        read = subprocess.run([python, "-I", "-c", "import sys, urllib.request; sys.stdout.buffer.write(urllib.request.urlopen(sys.argv[1]).read())", url],
                              capture_output=True, preexec_fn=become_nobody, timeout=30)
        assert read.returncode == 0, read.stderr.decode()[-500:]
        assert hashlib.sha256(read.stdout).hexdigest() == derived
    finally:
        shutil.rmtree(shared)


def test_a_derived_image_planted_as_a_link_is_replaced_not_sent(frames, tmp_path):
    # The name is predictable (the hash of the derived bytes): a link left under it in a run
    # folder would have the model server read the file it points at.
    store = ImageStore()
    derived = store.derive(store.add_file(frames[0]).image_hash, "marker", marked).image_hash
    private = tmp_path / "private.png"
    Image.new("RGB", (8, 8), (1, 2, 3)).save(private)
    before = private.read_bytes()
    cache = tmp_path / "cache"
    cache.mkdir()
    os.symlink(private, cache / f"{derived}.png")
    url = FileTransport(cache).url(store, derived)
    written = cache / f"{derived}.png"
    assert url == written.as_uri() and not written.is_symlink()
    assert hashlib.sha256(written.read_bytes()).hexdigest() == derived and private.read_bytes() == before


def test_the_default_derived_image_folder_planted_as_a_link_is_refused(release, tmp_path):
    from povagent.config.models import DEFAULT_CACHE_DIR, ImagesSpec
    from povagent.errors import WriteTargetError
    from povagent.exchange.transport import open_image_transport

    run = tmp_path / "run"
    run.mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    os.symlink(elsewhere, run / DEFAULT_CACHE_DIR)
    with (
        pytest.raises(WriteTargetError, match=rf"{DEFAULT_CACHE_DIR}: is a symbolic link"),
        open_image_transport(ImagesSpec(transport="file"), ImageStore(), dataset_root=release, output=run),
    ):
        pass
