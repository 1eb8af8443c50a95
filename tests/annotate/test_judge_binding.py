"""Judge mode binds each judgement to the judged run, and writes only where it was told: two
sweeps whose cells share names share no item, and a link planted at the default ``judgements/``
folder is refused, nothing written through it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from povagent.annotate.judge_page import JudgePage, judge_items
from povagent.annotate.server import AnnotateServer
from povagent.annotate.study_config import load_study
from povagent.errors import ReadTargetError, WriteTargetError
from povagent.results.judgements import Judgement, JudgementJournal

pytestmark = pytest.mark.timeout(300)

REALWORLD_DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"


@pytest.fixture(scope="module")
def two_sweeps(tmp_path_factory):
    """One run of the centre baseline on the demo real-world set, copied as the cell ``a`` of
    two sweeps (each copy's config names its own output, as a sweep writes it)."""
    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    base = tmp_path_factory.mktemp("judged")
    (base / "pipeline.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(REALWORLD_DEMO)}, "backend": "center", "strategy": "basic", "parser": "json",
        "scorers": ["success"], "output": str(base / "made"),
    }))  # fmt: skip
    run_pipeline(load_pipeline(base / "pipeline.yaml"))
    cells = []
    for sweep in ("sweep-x", "sweep-y"):
        cell = base / sweep / "a"
        shutil.copytree(base / "made", cell)
        config = cell / "config.yaml"
        config.write_text(config.read_text().replace(str(base / "made"), str(cell)))
        cells.append(cell)
    return base, cells


def test_cells_of_the_same_name_in_two_sweeps_share_no_item(two_sweeps):
    _, (x, y) = two_sweeps
    in_x, in_y = judge_items([x]).items, judge_items([y]).items
    assert in_x and len(in_x) == len(in_y)
    assert {i.run_name for i in in_x} == {i.run_name for i in in_y} == {"a"}
    assert not {i.item for i in in_x} & {i.item for i in in_y}


def test_after_judging_one_sweep_a_session_on_the_other_shows_all_its_predictions(two_sweeps, tmp_path):
    _, (x, y) = two_sweeps
    journal = JudgementJournal(tmp_path, "carol")
    for it in judge_items([x]).items:
        journal.append(Judgement(item=it.item, judge="carol", verdict="success", seconds=1.0, system=it.system, run_name=it.run_name,
                                 key=it.key, instance_id=it.instance_id, condition=it.condition))  # fmt: skip
    assert JudgePage(judge_items([x]), journal, "carol").state()["finished"]
    on_y = JudgePage(judge_items([y]), journal, "carol")
    assert on_y.state()["done"] == 0 and on_y.total == len(judge_items([y]).items)


def test_a_link_planted_at_the_default_judgements_folder_is_refused_and_nothing_written(two_sweeps, tmp_path):
    _, (x, _) = two_sweeps
    outside = tmp_path / "outside"
    outside.mkdir()
    study_file = x.parent / "carol.yaml"
    study_file.write_text(yaml.safe_dump({"judge": "carol", "runs": ["a"]}))
    study = load_study(study_file)
    before = JudgementJournal(study.judgements, study.judge, study.judgements_below)  # no folder yet
    link = x.parent / "judgements"
    link.symlink_to(outside, target_is_directory=True)
    try:
        with pytest.raises(ReadTargetError, match="symbolic link"):  # a session starting now stops before serving
            JudgementJournal(study.judgements, study.judge, study.judgements_below)
        item = judge_items([x]).items[0]
        with pytest.raises(WriteTargetError, match="symbolic link"):  # one planted mid-session: nothing written
            before.append(Judgement(item=item.item, judge="carol", verdict="success", seconds=1.0, system=item.system,
                                    run_name=item.run_name, key=item.key, instance_id=item.instance_id, condition=item.condition))  # fmt: skip
        assert list(outside.iterdir()) == []
    finally:
        link.unlink()


def test_a_judge_note_with_a_lone_surrogate_is_refused_and_nothing_written(two_sweeps, tmp_path):
    import http.client

    _, (x, _) = two_sweeps
    lines: list[str] = []
    page = JudgePage(judge_items([x]), JudgementJournal(tmp_path, "carol"), "carol")
    page.state()
    try:
        server = AnnotateServer(page, client_timeout=5.0, log=lines.append)
    except TypeError:  # the server before its log
        server = AnnotateServer(page, client_timeout=5.0)
    server.start()
    try:
        conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=30)
        path = server.url.removeprefix(f"http://127.0.0.1:{server.port}").split("?")[0] + "api/judge"
        conn.request("POST", path, body=b'{"question": 0, "verdict": "success", "note": "\\ud800"}',
                     headers={"Host": f"127.0.0.1:{server.port}", "X-Povagent-Token": server.token})  # fmt: skip
        status = conn.getresponse().status
    finally:
        server.close()
    assert status == 400 and len(lines) == 1
    assert not (tmp_path / "carol.jsonl").exists() or (tmp_path / "carol.jsonl").read_text() == ""
