"""The loopback Hub server speaks the part of the Hub's file API huggingface_hub relies on."""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.request

import pytest

from povagent.testing.hub_server import HubServer, git_blob_id

FILES = {
    "meta.json": b'{"version": "test"}',
    "artifacts/h0/h0.json": b"[]",
    "artifacts/h0/exploration_images/frame_000.png": b"\x89PNG fake frame",
    "artifacts/h0/img_from_observer/pair_0.png": b"\x89PNG fake view",
}


def fetch(url: str, method: str = "GET", headers: dict[str, str] | None = None):
    req = urllib.request.Request(url, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=5) as resp:
            return resp.status, dict(resp.headers), resp.read()
    except urllib.error.HTTPError as err:
        return err.code, dict(err.headers), err.read()


@pytest.fixture
def server():
    with HubServer(files=FILES, max_lifetime_s=30) as s:
        yield s


def test_repo_info_names_the_commit_and_every_file(server):
    status, _, body = fetch(f"{server.url}/api/datasets/owl-owl/POVBench/revision/main")
    info = json.loads(body)
    assert status == 200 and info["sha"] == server.commit and len(info["sha"]) == 40
    assert [s["rfilename"] for s in info["siblings"]] == sorted(FILES)


def test_the_commit_hash_is_a_revision_too_and_depends_on_the_files(server):
    status, _, body = fetch(f"{server.url}/api/datasets/owl-owl/POVBench/revision/{server.commit}")
    assert status == 200 and json.loads(body)["sha"] == server.commit
    other = HubServer(files={**FILES, "meta.json": b"{}"})
    assert other.commit != server.commit


def test_unknown_revision_and_repository_carry_the_hub_error_codes(server):
    status, headers, _ = fetch(f"{server.url}/api/datasets/owl-owl/POVBench/revision/v9")
    assert status == 404 and headers["X-Error-Code"] == "RevisionNotFound"
    status, headers, _ = fetch(f"{server.url}/api/datasets/owl-owl/Other/revision/main")
    assert status == 404 and headers["X-Error-Code"] == "RepoNotFound"
    # the same repository id as a model repository does not exist either
    status, headers, _ = fetch(f"{server.url}/api/models/owl-owl/POVBench/revision/main")
    assert status == 404 and headers["X-Error-Code"] == "RepoNotFound"


def test_resolve_head_sends_the_headers_the_client_checks(server):
    path = "artifacts/h0/img_from_observer/pair_0.png"
    status, headers, body = fetch(f"{server.url}/datasets/owl-owl/POVBench/resolve/main/{path}", "HEAD")
    data = FILES[path]
    assert status == 200 and body == b""
    assert headers["X-Repo-Commit"] == server.commit
    assert headers["ETag"] == f'"{git_blob_id(data)}"'
    assert int(headers["Content-Length"]) == len(data)


def test_resolve_get_sends_the_bytes_and_honours_a_range(server):
    path = "artifacts/h0/exploration_images/frame_000.png"
    url = f"{server.url}/datasets/owl-owl/POVBench/resolve/{server.commit}/{path}"
    assert fetch(url)[2] == FILES[path]
    status, headers, body = fetch(url, headers={"Range": "bytes=5-"})
    assert status == 206 and body == FILES[path][5:]
    assert headers["Content-Range"] == f"bytes 5-{len(FILES[path]) - 1}/{len(FILES[path])}"
    assert server.fetched_files() == [path, path]


def test_a_missing_file_is_entry_not_found_with_the_commit(server):
    status, headers, _ = fetch(f"{server.url}/datasets/owl-owl/POVBench/resolve/main/nope.json", "HEAD")
    assert status == 404 and headers["X-Error-Code"] == "EntryNotFound"
    assert headers["X-Repo-Commit"] == server.commit


def test_git_blob_id_is_gits_object_id():
    # `printf 'hello\n' | git hash-object --stdin`
    assert git_blob_id(b"hello\n") == "ce013625030ba8dba906f756967f9e9ca394464a"


def test_tree_listing_is_paged_with_link_headers():
    with HubServer(files=FILES, page_size=3, max_lifetime_s=30) as s:
        url = f"{s.url}/api/datasets/owl-owl/POVBench/tree/main?recursive=true&expand=false"
        entries = []
        pages = 0
        while url:
            status, headers, body = fetch(url)
            assert status == 200
            entries += json.loads(body)
            pages += 1
            link = headers.get("Link")
            url = link.split(">")[0].lstrip("<") if link else None
    files = [e["path"] for e in entries if e["type"] == "file"]
    folders = [e["path"] for e in entries if e["type"] == "directory"]
    assert sorted(files) == sorted(FILES) and pages == 3
    assert set(folders) == {"artifacts", "artifacts/h0", "artifacts/h0/exploration_images", "artifacts/h0/img_from_observer"}
    sizes = {e["path"]: e["size"] for e in entries if e["type"] == "file"}
    assert sizes == {p: len(b) for p, b in FILES.items()}


def test_a_non_recursive_listing_holds_one_level(server):
    _, _, body = fetch(f"{server.url}/api/datasets/owl-owl/POVBench/tree/main?recursive=false")
    assert {e["path"] for e in json.loads(body)} == {"meta.json", "artifacts"}


def test_a_stopped_server_refuses_connections_even_kept_alive_ones(server):
    import http.client

    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=5)
    conn.request("GET", "/api/datasets/owl-owl/POVBench/revision/main")
    assert conn.getresponse().read()
    server.stop()
    with pytest.raises((ConnectionError, http.client.HTTPException, OSError)):
        conn.request("GET", "/api/datasets/owl-owl/POVBench/revision/main")
        conn.getresponse().read()
    with pytest.raises(urllib.error.URLError):
        urllib.request.urlopen(f"{server.url}/api/datasets/owl-owl/POVBench/revision/main", timeout=5)


def test_the_server_stops_by_itself_after_its_lifetime():
    s = HubServer(files=FILES, max_lifetime_s=0.3).start()
    deadline = time.monotonic() + 5
    while s._server is not None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert s._server is None


def test_exactly_one_source_of_files():
    with pytest.raises(ValueError):
        HubServer()
    with pytest.raises(ValueError):
        HubServer("x", files=FILES)


def test_an_injected_outage_answers_every_request_with_its_status(server):
    server.fail_status = 503
    assert fetch(f"{server.url}/api/datasets/owl-owl/POVBench/revision/main")[0] == 503
    assert fetch(f"{server.url}/datasets/owl-owl/POVBench/resolve/main/meta.json", "HEAD")[0] == 503
    server.fail_status = None
    assert fetch(f"{server.url}/api/datasets/owl-owl/POVBench/revision/main")[0] == 200


def test_a_malformed_cursor_is_a_bad_request(server):
    assert fetch(f"{server.url}/api/datasets/owl-owl/POVBench/tree/main?cursor=x")[0] == 400


def test_lfs_files_are_listed_and_answered_as_the_hub_does():
    import hashlib

    from povagent.testing.hub_server import lfs_pointer

    frame = "artifacts/h0/exploration_images/frame_000.png"
    with HubServer(files=FILES, lfs_patterns=["*.png"], max_lifetime_s=30) as s:
        _, _, body = fetch(f"{s.url}/api/datasets/owl-owl/POVBench/tree/main?recursive=true")
        entry = next(e for e in json.loads(body) if e["path"] == frame)
        _, headers, _ = fetch(f"{s.url}/datasets/owl-owl/POVBench/resolve/main/{frame}", method="HEAD")
    sha256 = hashlib.sha256(FILES[frame]).hexdigest()
    assert entry["lfs"] == {"oid": sha256, "size": len(FILES[frame]), "pointerSize": len(lfs_pointer(FILES[frame]))}
    assert entry["oid"] == git_blob_id(lfs_pointer(FILES[frame]))  # git holds the pointer
    assert headers["X-Linked-Etag"] == f'"{sha256}"' and headers["X-Linked-Size"] == str(len(FILES[frame]))


def test_lies_change_what_the_server_says_and_nothing_else():
    from povagent.testing.hub_server import HubLies

    lies = HubLies(sha="../x", etag="../e", repo_commit="/abs", served={"meta.json": b"other"}, missing={"artifacts/h0/h0.json"})
    with HubServer(files=FILES, lies=lies, max_lifetime_s=30) as s:
        _, _, info = fetch(f"{s.url}/api/datasets/owl-owl/POVBench/revision/main")
        status, headers, body = fetch(f"{s.url}/datasets/owl-owl/POVBench/resolve/main/meta.json")
        missing, missing_headers, _ = fetch(f"{s.url}/datasets/owl-owl/POVBench/resolve/main/artifacts/h0/h0.json")
        _, _, tree = fetch(f"{s.url}/api/datasets/owl-owl/POVBench/tree/main?recursive=true")
    assert json.loads(info)["sha"] == "../x"
    assert status == 200 and body == b"other" and headers["ETag"] == '"../e"' and headers["X-Repo-Commit"] == "/abs"
    assert missing == 404 and missing_headers["X-Repo-Commit"] == "/abs"
    listed = {e["path"]: e for e in json.loads(tree) if e["type"] == "file"}
    assert listed["meta.json"]["size"] == len(FILES["meta.json"])  # the listing still tells the truth


def test_stopping_the_server_ends_a_stalled_transfer_at_once():
    import threading

    from povagent.testing.hub_server import HubLies

    s = HubServer(files=FILES, lies=HubLies(stall_s=60), max_lifetime_s=90).start()
    def read() -> None:
        try:
            fetch(f"{s.url}/datasets/owl-owl/POVBench/resolve/main/meta.json")
        except OSError:  # the body is cut when the server stops: what a client of a dead server sees
            pass

    reader = threading.Thread(target=read)
    reader.start()
    time.sleep(0.5)
    start = time.monotonic()
    s.stop()
    reader.join(10)
    assert not reader.is_alive() and time.monotonic() - start < 5
