"""A held-out-style set of hostile inputs: each ends in a clear message, and nothing is lost.

Bad datasets, bad configs, bad model answers and bad prediction files, each through the
command a user would type (``validate``, ``run``, ``score``, ``report``). For every case:

* no traceback: the command exits normally, or with a user-facing :class:`PovagentError`
  (what ``povagent`` prints as ``error: ...``);
* the message names the file at fault (and, for dataset files, the field);
* nothing is lost: a config refused on a run folder leaves its rows byte for byte; a bad house
  costs only its own rows; every answer of a hostile model is a row; the report is written.

The cases are tables: add a row to cover a new attack.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any, Callable

import pytest
import yaml
from PIL import Image
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import PovagentError
from povagent.testing.loopback_server import LoopbackServer

pytestmark = pytest.mark.timeout(120)

TARGET = "train_house_00001"  # the house each dataset case damages
#: Instances of the untouched house train_house_00000 (1 pair, 4 directions, 3 conditions).
GOOD_HOUSE_INSTANCES = 12


def invoke(*args: str) -> tuple[int, str]:
    """Run a command as ``povagent`` would: (exit code, everything it printed or raised)."""
    result = CliRunner().invoke(app, [str(a) for a in args])
    text = result.output + (getattr(result, "stderr", "") if getattr(result, "stderr_bytes", None) is not None else "")
    exc = result.exception
    if exc is not None and not isinstance(exc, SystemExit):
        assert isinstance(exc, PovagentError), f"traceback instead of a message: {type(exc).__name__}: {exc}"
        return 2, text + f"error: {exc}"
    assert "Traceback" not in text
    return result.exit_code, text


@pytest.fixture
def dataset(dataset_copy) -> Path:
    return dataset_copy


def house(root: Path, name: str | None = None) -> Path:
    return root / "artifacts" / TARGET / (name or f"{TARGET}.json")


def edit(path: Path, change: Callable[[Any], None]) -> None:
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


def _outside(root: Path) -> Path:
    secret = root.parent / "secret.png"
    Image.new("RGB", (512, 512), (255, 0, 0)).save(secret)
    return secret


def _symlinked_frame(root: Path) -> None:
    frame = house(root, "exploration_images/frame_000.png")
    frame.unlink()
    os.symlink(_outside(root), frame)


def _symlinked_log(root: Path) -> None:
    outside = root.parent / "log.json"
    shutil.copy(house(root, "exploration_log.json"), outside)
    house(root, "exploration_log.json").unlink()
    os.symlink(outside, house(root, "exploration_log.json"))


def _rgb_path_climbing_through_a_symlinked_folder(root: Path) -> None:
    # ``deep`` looks one level down but is four: the path resolves back inside the dataset
    # (to the pair's own view), while as written it climbs out of the dataset folder.
    target = house(root, "img_from_observer/a/b")
    target.mkdir(parents=True)
    os.symlink(target, house(root, "deep"))
    edit(house(root), lambda d: d[0].update(rgb_path=f"deep/../../../../../artifacts/{TARGET}/img_from_observer/pair_7.png"))


#: name -> (damage, file named in the messages, field named or None)
DATASETS: dict[str, tuple[Callable[[Path], None], str, str | None]] = {
    "absolute image_path": (
        lambda r: edit(house(r, "exploration_log.json"), lambda d: d[0].update(image_path=str(_outside(r)))),
        "exploration_log.json",
        "$[0].image_path",
    ),
    "rgb_path climbing out": (lambda r: edit(house(r), lambda d: d[0].update(rgb_path="../../../secret.png")), f"{TARGET}.json", "$[0].rgb_path"),
    "rgb_path climbing out through a symlinked folder": (_rgb_path_climbing_through_a_symlinked_folder, f"{TARGET}.json", "$[0].rgb_path"),
    "frame symlinked out": (_symlinked_frame, "exploration_log.json", "$[0].image_path"),
    "log symlinked out": (_symlinked_log, "exploration_log.json", None),
    "NaN camera position": (
        lambda r: edit(house(r), lambda d: d[0]["camera"]["cam_pos"].__setitem__(0, float("nan"))),
        f"{TARGET}.json",
        "$[0].camera.cam_pos[0]",
    ),
    "infinite yaw": (
        lambda r: edit(house(r, "exploration_log.json"), lambda d: d[1]["camera"].update(cam_yaw=float("inf"))),
        "exploration_log.json",
        "$[1].camera.cam_yaw",
    ),
    "truncated frame": (
        lambda r: house(r, "exploration_images/frame_001.png").write_bytes(house(r, "exploration_images/frame_001.png").read_bytes()[:300]),
        "exploration_log.json",
        "$[1].image_path",
    ),
    "observer view of the wrong size": (
        lambda r: Image.new("RGB", (300, 200)).save(house(r, "img_from_observer/pair_7.png")),
        f"{TARGET}.json",
        "$[0].rgb_path",
    ),
    "frame that is not an image": (lambda r: house(r, "exploration_images/frame_000.png").write_text("GIF? no."), "exploration_log.json", "$[0].image_path"),
    "pair file not JSON": (lambda r: house(r).write_text("{pairs: oops"), f"{TARGET}.json", None),
    "pair file nested 100000 deep": (lambda r: house(r).write_text("[" * 100000 + "]" * 100000), f"{TARGET}.json", None),
    "pair file not UTF-8": (lambda r: house(r).write_bytes(b'[{"pair_id": "\xff"}]'), f"{TARGET}.json", None),
    "log is an object": (lambda r: house(r, "exploration_log.json").write_text('{"frames": []}'), "exploration_log.json", None),
    "lone surrogate in a sentence": (
        lambda r: edit(house(r), lambda d: d[0]["stage5"]["front"].update(type_a="the remote \ud800")),
        f"{TARGET}.json",
        "$[0].stage5.front.type_a",
    ),
    "pair with an absurd screen size": (
        lambda r: edit(house(r), lambda d: d[0]["camera"].update(screen_width=10**9)),
        f"{TARGET}.json",
        "$[0].camera.screen_width",
    ),
}


@pytest.mark.parametrize("damage, file, field", DATASETS.values(), ids=DATASETS.keys())
def test_a_bad_dataset_is_reported_by_file_and_the_run_keeps_the_good_house(tmp_path, dataset, damage, file, field):
    damage(dataset)
    code, text = invoke("validate", dataset)
    assert code == 1 and f"{TARGET}/{file}" in text and (field is None or field in text), text

    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({"dataset": str(dataset), "backend": "center", "cache": False, "output": str(tmp_path / "run")}))
    code, text = invoke("run", pipeline, "--quiet")
    assert code == 0 and file in text, text
    rows = (tmp_path / "run" / "results.jsonl").read_text().splitlines()
    houses = {json.loads(r)["house_id"] for r in rows}
    assert "train_house_00000" in houses and len([r for r in rows if "train_house_00000" in r]) == GOOD_HOUSE_INSTANCES

    code, text = invoke("run", pipeline, "--quiet", "--strict")
    assert code == 2 and file in text, text


def _billion_laughs() -> str:
    lines = ['a0: &a0 "lol"'] + [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 10)]
    return "\n".join(lines) + "\n"


#: name -> (text or bytes appended to / replacing a good pipeline, words the message holds)
CONFIGS: dict[str, tuple[Callable[[str], str | bytes], str]] = {
    "billion laughs": (lambda good: _billion_laughs() + good, "alias"),
    "runs: 100000000": (lambda good: good + "runs: 100000000\n", "runs"),
    "latin-1 bytes": (lambda good: good.encode() + "x: caf\xe9\n".encode("latin-1"), "UTF-8"),
    "binary": (lambda good: bytes(range(256)) * 8, "UTF-8"),
    "20000-deep nesting": (lambda good: good + "x: " + "[" * 20000 + "]" * 20000 + "\n", "nested"),
    "infinite retry wait": (lambda good: good + "retry: {initial_wait: .inf}\n", "initial_wait"),
    "NaN timeout": (lambda good: good + "timeout: .nan\n", "timeout"),
    "10 MB value": (lambda good: good + "x: '" + "a" * 10_000_000 + "'\n", "MiB"),
    "duplicate key": (lambda good: good + "backend: random\n", "twice"),
    "profile typo in backend options": (
        lambda good: good.replace("backend: center", "backend: {name: litellm, options: {model: qwen3-vl8b, api_base: 'http://127.0.0.1:9/v1'}}"),
        "did you mean 'qwen3-vl-8b'",
    ),
    "key pasted into api_key_env": (
        lambda good: good.replace("backend: center", "backend: {name: litellm, options: {model: openai/m, api_key_env: sk-abc123}}"),
        "api_key_env",
    ),
    "unknown key": (lambda good: good + "stratgy: cot\n", "did you mean 'strategy'"),
    "empty file": (lambda good: "", "mapping"),
    "a list, not a mapping": (lambda good: "- dataset: x\n", "mapping"),
    "missing plugin module": (lambda good: good + "plugins: [no_such_module_xyz]\n", "no_such_module_xyz"),
    "plugin at an absolute path": (lambda good: good + "plugins: [/usr/lib/hostile_plugin.py]\n", "outside the config's folder"),
    "plugin climbing out with ../": (lambda good: good + "plugins: [../../hostile_plugin.py]\n", "outside the config's folder"),
    "control character": (lambda good: good + "x: \x07\n", "control character"),
}


@pytest.fixture
def finished_run(tmp_path, finished_run_once) -> tuple[Path, str, bytes]:
    """A finished run: its folder (a copy of the module's one run of the two good houses, so each
    case has a run of its own to leave untouched), the good pipeline's text naming that copy as
    its output, and its results file's bytes."""
    source, _ = finished_run_once
    shutil.copytree(source, tmp_path / "run", symlinks=True)
    good = yaml.safe_dump({"dataset": str(source.parent / "ds"), "backend": "center", "cache": False, "output": str(tmp_path / "run")},
                          sort_keys=False)  # fmt: skip
    return tmp_path / "run", good, (tmp_path / "run" / "results.jsonl").read_bytes()


@pytest.mark.parametrize("make, words", CONFIGS.values(), ids=CONFIGS.keys())
def test_a_bad_config_is_refused_naming_the_file_and_the_run_folder_is_untouched(tmp_path, finished_run, make, words):
    run_dir, good, before = finished_run
    bad = tmp_path / "bad.yaml"
    content = make(good)
    bad.write_bytes(content if isinstance(content, bytes) else content.encode())
    code, text = invoke("run", bad, "--quiet")
    assert code == 2 and str(bad) in text and words in text, text[:3000]
    assert len(text) < 10_000  # a 10 MB value is not echoed
    assert "sk-abc123" not in text
    assert (run_dir / "results.jsonl").read_bytes() == before


#: name -> what the model answers to every request
ANSWERS: dict[str, str] = {
    "NaN and Infinity": '{"selected_image": 0, "x": NaN, "y": Infinity}',
    "numbers past float range": '{"selected_image": 1e400, "x": 1e999, "y": -1e999}',
    "a megabyte of text": "Let me think. " * 80_000 + '{"selected_image": 0, "x": 10, "y": 10}',
    "100000 open braces": "{" * 100_000,
    "nested JSON 10000 deep": '{"x": ' * 10_000 + "1" + "}" * 10_000,
    "script tag and control characters": '</script><script>alert(1)</script>\x00\x1b[31m {"selected_image": 0, "x": 1, "y": 2}',
    "wrong types": '{"selected_image": [0], "x": {"v": 1}, "y": null}',
    "empty": "",
    "a lone surrogate": '{"selected_image": 0, "x": 1, "y": 2} \ud800',
}


@pytest.fixture(scope="module")
def answer_server():
    with LoopbackServer(max_lifetime_s=110) as server:
        yield server


@pytest.mark.parametrize("answer", ANSWERS.values(), ids=ANSWERS.keys())
def test_a_hostile_answer_is_a_row_and_the_report_is_written(tmp_path, dataset, answer_server, answer, monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-secret-123")
    answer_server.reply = answer
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({
        "dataset": str(dataset),
        "instances": {"houses": [TARGET], "conditions": ["a", "c"]},
        "backend": {"name": "litellm", "options": {"model": "openai/hostile", "api_base": answer_server.url, "api_key_env": "POVAGENT_TEST_KEY"}},
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "cache": False,
        "output": str(tmp_path / "run"),
    }))
    code, text = invoke("run", pipeline, "--quiet")
    assert code == 0, text[-3000:]
    rows = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 4 and all(r["status"] in ("answered", "parse_error") for r in rows), [r["status"] for r in rows]
    code, text = invoke("report", tmp_path / "run", "--out", tmp_path / "report", "--bootstrap", "0")
    assert code == 0 and (tmp_path / "report" / "report.html").exists(), text[-3000:]
    assert "<script>alert(1)</script>" not in (tmp_path / "report" / "report.html").read_text()


def test_a_server_that_answers_nothing_fails_the_keys_and_writes_nothing_wrong(tmp_path, dataset, answer_server, monkeypatch):
    # content null / no choices: not an (empty) answer to keep, a failure to retry and record
    from povagent.testing.loopback_server import Reply

    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-secret-123")
    answer_server.reply = Reply(None)
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({
        "dataset": str(dataset),
        "instances": {"houses": [TARGET], "conditions": ["a", "c"]},
        "backend": {"name": "litellm", "options": {"model": "openai/hostile", "api_base": answer_server.url, "api_key_env": "POVAGENT_TEST_KEY"}},
        "retry": {"attempts": 2, "initial_wait": 0.0, "max_wait": 0.0},
        "output": str(tmp_path / "run"),
    }))
    code, text = invoke("run", pipeline, "--quiet")
    assert code == 3, text[-3000:]  # keys failed: the documented exit code
    rows = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 4 and {r["error_type"] for r in rows} == {"empty_response"}
    assert "run `povagent run" in text or "again" in text


def test_a_key_echoed_inside_a_successful_answer_reaches_no_file(tmp_path, dataset, answer_server, monkeypatch):
    # The variable's name matches no secret-looking pattern: only knowing api_key_env finds it.
    from povagent.testing.loopback_server import Reply

    key = "lab-key-4f9a8c7e2b1d"
    monkeypatch.setenv("POVAGENT_ECHO_VAR", key)

    def echo(request):
        sent = request.headers.get("authorization", "")
        return Reply('{"selected_image": 0, "x": 256, "y": 256} (you sent ' + sent + ")")

    answer_server.reply = echo
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({
        "dataset": str(dataset),
        "instances": {"houses": [TARGET], "conditions": ["a", "c"]},
        "backend": {"name": "litellm", "options": {"model": "openai/echo", "api_base": answer_server.url, "api_key_env": "POVAGENT_ECHO_VAR"}},
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "output": str(tmp_path / "run"),
    }))
    code, text = invoke("run", pipeline, "--quiet")
    assert code == 0, text[-3000:]
    assert answer_server.requests and key in answer_server.requests[-1].headers["authorization"]  # it was sent
    rows = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 4 and all("[REDACTED]" in r["exchanges"][-1]["raw"] for r in rows)
    assert all(r["status"] == "answered" for r in rows)  # the answer itself is kept exactly
    code, _ = invoke("run", pipeline, "--quiet")  # again: every answer now from the cache
    assert code == 0
    assert invoke("report", tmp_path / "run", "--bootstrap", "0")[0] == 0
    assert invoke("rescore", tmp_path / "run")[0] == 0
    written = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert any(p.name == "cache.sqlite" for p in written) and any(p.name == "report.html" for p in written)
    assert [str(p) for p in written if key.encode() in p.read_bytes()] == []


#: name -> an official predictions file's text
PREDICTIONS: dict[str, str] = {
    "not JSON": "[{house_id: 1",
    "NaN coordinates": '[{"house_id": "train_house_00001", "pair_id": "7", "direction": "front", "type": "c", "predicted_x": NaN, "predicted_y": Infinity}]',
    "wrong types": '[{"house_id": ["x"], "pair_id": {}, "direction": 3, "type": null, "predicted_x": "left"}]',
    "a number, not rows": "42",
    "deeply nested": "[" * 50_000 + "]" * 50_000,
}


@pytest.mark.parametrize("text", PREDICTIONS.values(), ids=PREDICTIONS.keys())
def test_a_bad_predictions_file_is_scored_or_refused_with_its_name(tmp_path, dataset, text):
    path = tmp_path / "predictions.json"
    path.write_text(text)
    code, output = invoke("score", "--predictions", path, "--dataset", dataset)
    assert code in (0, 2), output
    assert code == 0 or str(path) in output or "predictions.json" in output, output


@pytest.fixture(scope="module")
def finished_run_once(tmp_path_factory, mini_root) -> tuple[Path, Path]:
    """One finished run of the two good houses (its folder, its pipeline), copied by each case."""
    base = tmp_path_factory.mktemp("finished")
    root = base / "ds"
    (root / "artifacts").mkdir(parents=True)
    shutil.copy(mini_root / "meta.json", root / "meta.json")
    for name in ("train_house_00000", TARGET):
        shutil.copytree(mini_root / "artifacts" / name, root / "artifacts" / name)
    pipeline = base / "good.yaml"
    pipeline.write_text(yaml.safe_dump({"dataset": str(root), "backend": "center", "cache": False, "output": str(base / "run")}))
    code, text = invoke("run", pipeline, "--quiet")
    assert code == 0, text
    return base / "run", pipeline


def _plant_link(rel: str, to_folder: bool = False) -> Callable[[Path, Path], None]:
    def plant(run: Path, outside: Path) -> None:
        (run / rel).parent.mkdir(parents=True, exist_ok=True)
        (run / rel).unlink(missing_ok=True)  # the file povagent wrote, swapped for a link
        os.symlink(outside.parent if to_folder else outside, run / rel)

    return plant


def _plant_folder(rel: str) -> Callable[[Path, Path], None]:
    return lambda run, outside: (run / rel).mkdir(parents=True)


def _plant_file(rel: str) -> Callable[[Path, Path], None]:
    return lambda run, outside: (run / rel).write_text("someone's file")


#: name -> (command after the run folder, what is planted in the run folder, the entry the one
#: line names, or None where the writer replaces the link without following it and succeeds)
RUN_FOLDER_PLANTS: dict[str, tuple[tuple[str, ...], Callable[[Path, Path], None], str | None]] = {
    "rescored folder linked out": (("rescore",), _plant_link("rescored-official", to_folder=True), "rescored-official"),
    "rescore's staged rows linked out": (("rescore",), _plant_link("rescored-official/results.jsonl.tmp"), None),
    "rescore's config linked out": (("rescore",), _plant_link("rescored-official/config.yaml"), None),
    "rescore's summary staging linked out": (("rescore",), _plant_link("rescored-official/summary.json.tmp"), None),
    "rescored folder is a file": (("rescore",), _plant_file("rescored-official"), "rescored-official"),
    "rescore's staged rows are a folder": (("rescore",), _plant_folder("rescored-official/results.jsonl.tmp"), "results.jsonl.tmp"),
    "rescore's rows are a folder": (("rescore",), _plant_folder("rescored-official/results.jsonl"), "results.jsonl"),
    "rescore's summary is a folder": (("rescore",), _plant_folder("rescored-official/summary.json"), "summary.json"),
    "resumed run's log linked out": (("run",), _plant_link("log.jsonl"), "log.jsonl"),
    "resumed run's journal linked out": (("run",), _plant_link("results.jsonl"), "results.jsonl"),
    "resumed run's summary linked out": (("run",), _plant_link("summary.json"), None),
    "report folder linked out": (("report", "--bootstrap", "0"), _plant_link("report", to_folder=True), "report"),
    "report page linked out": (("report", "--bootstrap", "0"), _plant_link("report/report.html"), None),
    "report summary linked out": (("report", "--bootstrap", "0"), _plant_link("report/summary.json"), None),
    "official export linked out": (("export",), _plant_link("official_predictions.json"), None),
    "official export's staging linked out": (("export",), _plant_link("official_predictions.json.tmp"), None),
    "long CSV linked out": (("export", "--format", "long-csv"), _plant_link("all_runs_long.csv"), None),
}


@pytest.mark.parametrize("command, plant, named", RUN_FOLDER_PLANTS.values(), ids=RUN_FOLDER_PLANTS.keys())
def test_a_link_planted_in_a_run_folder_never_writes_outside_it(tmp_path, finished_run_once, command, plant, named):
    source, pipeline = finished_run_once
    run = tmp_path / "run"
    shutil.copytree(source, run, symlinks=True)
    outside = tmp_path / "elsewhere" / "precious.txt"
    outside.parent.mkdir()
    outside.write_text("keep me\n")
    plant(run, outside)
    if command[0] == "run":  # the same pipeline pointed at the copy resumes it
        resumed = tmp_path / "pipeline.yaml"
        resumed.write_text(pipeline.read_text().replace(str(source), str(run)))
        code, text = invoke("run", resumed, "--quiet")
    else:
        code, text = invoke(command[0], run, *command[1:])
    assert outside.read_text() == "keep me\n" and sorted(p.name for p in outside.parent.iterdir()) == ["precious.txt"], text
    if named is None:
        assert code == 0, text[-3000:]
    else:
        error = [line for line in text.splitlines() if line.startswith("error:")]
        assert code == 2 and len(error) == 1 and f"{named}:" in error[0], text[-3000:]
