"""Each set scored by its own rule gives, per item and per aggregate, what the set's own code gives.

The canned replies below were run through the upstream code at the pinned commits (a scratch
script outside the project executed, on the same records and replies: ViewSpatial-Bench
``evaluate.py`` ``evaluate_vlm`` with its model call replaced by the reply; MindCube
``src/evaluation/evaluator.py`` ``BasicEvaluator.evaluate`` on a responses JSONL; VLMEvalKit
``_3DSRBench.evaluate``'s Flip / Circular block with ``report_acc`` on ``can_infer`` hits; the
authors' results script (SpatialReasoner ``src/eval/compute_3dsrbench_results.py`` @ 90eeb8ea, the
3DSRBench authors' circular evaluation); lmms-eval's ``3dsrbench`` aggregations). The numbers
pinned here are what they printed; povagent's ``run`` and ``rescore`` must give them.
"""

from __future__ import annotations

import json
import shutil

import pytest
import yaml
from PIL import Image

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import run_pipeline

from ..queued_runs import run_with_queued_replies
from .conftest import OFFLINE_PLUGIN

CAMERA = "Camera perspective - Relative Direction"
OBJECT = "Person perspective - Object View Orientation"
SCENE = "Person perspective - Scene Simulation Relative Direction"
PERSON = "Person perspective - Relative Direction"
VIEWSPATIAL = [  # question_type, answer, reply
    (CAMERA, "A. right", "A"), (CAMERA, "B. left", "B\n"), (CAMERA, "C. front", "<think>C is right</think>\nc"),
    (OBJECT, "D. back", "Looking again.\nD"), (OBJECT, "A. right", "I cannot tell."),
    (SCENE, "B. left", "<think>A</think>B"), (SCENE, "C. front", "The answer is C.\n"), (PERSON, "D. back", "d"),
]  # fmt: skip
#: evaluate.py's labels and its printed accuracies on the replies above
VIEWSPATIAL_LABELS = ["A", None, "C", "D", None, "A", None, "D"]
VIEWSPATIAL_ACCURACY = {CAMERA: 2 / 3, OBJECT: 0.5, SCENE: 0.0, PERSON: 1.0, "overall": 0.5}

MINDCUBE = [  # id, gold, reply
    ("among_group1_q1", "A", "<think>Maybe A. Keyboard</think>\nD"), ("among_group1_q2", "B", "b"),
    ("among_group2_q1", "C", "C. The window"), ("around_0001_q1", "D", "My answer is D."),
    ("aroundnew_0002_q1", "A", "I cannot tell from these views."), ("rotation_0003_q1", "B", "B"),
    ("rotation_0003_q2", "A", "The answer is B."), ("translation_0004_q1", "C", "C"), ("translation_0004_q2", "A", "A"),
    ("other_0005_q1", "B", "Answer: B"),
]  # fmt: skip
#: MindCube's evaluator's labels and accuracies (its overall leaves translation out: 5 / 8)
MINDCUBE_LABELS = ["A", None, "C", "D", None, "B", "B", "C", "A", "B"]
MINDCUBE_ACCURACY = {"among": 2 / 3, "around": 0.5, "rotation": 0.5, "translation": 1.0, "other": 1.0, "overall": 0.625}

FOUR = ("the lamp", "the clock", "both the same", "neither")
SRBENCH = [  # qid, options, answer, category, reply
    ("QUES0001", ("yes", "no"), "A", "height_higher", "A"),
    ("QUES0001-1", ("no", "yes"), "B", "height_higher", "The answer is B."),
    ("QUES0001-flip", ("yes", "no"), "B", "height_higher", "b"),
    ("QUES0001-flip-1", ("no", "yes"), "A", "height_higher", "A"),
    ("QUES0002", FOUR, "A", "location_above", "A"),
    ("QUES0002-1", FOUR[1:] + FOUR[:1], "B", "location_above", "I cannot tell."),
    ("QUES0002-2", FOUR[2:] + FOUR[:2], "C", "location_above", "C"),
    ("QUES0002-3", FOUR[3:] + FOUR[:3], "D", "location_above", "D"),
    ("QUES0003", ("yes", "no"), "A", "orientation_viewpoint", "<think>B</think>A"),
    ("QUES0003-1", ("no", "yes"), "B", "orientation_viewpoint", "B"),
    ("QUES0004", ("yes", "no"), "B", "orientation_on_the_left", "B"),
    ("QUES0004-flip", ("yes", "no"), "A", "orientation_on_the_left", "B"),
    ("QUES0005", FOUR, "C", "multi_object_facing", "C"),
    ("QUES0005-1", FOUR[1:] + FOUR[:1], "D", "multi_object_facing", "D"),
    ("QUES0005-2", FOUR[2:] + FOUR[:2], "A", "multi_object_facing", "A"),
    ("QUES0005-3", FOUR[3:] + FOUR[:3], "B", "multi_object_facing", "Answer: B"),
    ("QUES0006", ("yes", "no"), "A", "multi_object_parallel", "yes"),
    ("QUES0006-flip", ("yes", "no"), "B", "multi_object_parallel", "B"),
]
#: VLMEvalKit's _3DSRBench.evaluate (exact matching): each setting, overall and per sub-category
VLMEVALKIT = {
    "vanilla_accuracy": {"overall": 7 / 9, "height_higher": 0.75, "location_above": 0.75, "multi_object_facing": 1.0,
                         "multi_object_parallel": 1.0, "orientation_on_the_left": 0.5, "orientation_viewpoint": 0.5},
    "flip_accuracy": {"overall": 5 / 7, "height_higher": 0.5, "location_above": 0.75, "multi_object_facing": 1.0,
                      "multi_object_parallel": 1.0, "orientation_on_the_left": 0.0, "orientation_viewpoint": 0.5},
    "circular_accuracy": {"overall": 5 / 9, "height_higher": 0.5, "location_above": 0.0, "multi_object_facing": 1.0,
                          "multi_object_parallel": 1.0, "orientation_on_the_left": 0.5, "orientation_viewpoint": 0.0},
    "flip_circular_accuracy": {"overall": 1 / 3, "height_higher": 0.0, "location_above": 0.0, "multi_object_facing": 1.0,
                               "multi_object_parallel": 1.0, "orientation_on_the_left": 0.0, "orientation_viewpoint": 0.0},
}  # fmt: skip
#: the authors' circular evaluation per type, on VLMEvalKit's hits
AUTHORS_CIRCULAR_PER_TYPE = {"height": 0.5, "location": 0.0, "orientation": 1 / 3, "multi_object": 1.0}
#: lmms-eval's per-type vanilla aggregation on VLMEvalKit's hits
VANILLA_PER_TYPE = {"height": 0.75, "location": 0.75, "orientation": 0.5, "multi_object": 1.0}
#: lmms-eval's 3dsrbench task (its reading, its aggregations)
LMMS_EVAL = {"vanilla_accuracy": 7 / 9, "flip_accuracy": 5 / 7, "circular_accuracy": 5 / 9, "flip_circular_accuracy": 1 / 3}
LMMS_EVAL_VANILLA = {"height": 0.75, "location": 0.75, "orientation": 0.75, "multi_object": 5 / 6, "height_higher": 0.75,
                     "location_above": 0.75, "multi_object_facing": 1.0, "multi_object_parallel": 0.5,
                     "orientation_on_the_left": 0.5, "orientation_viewpoint": 1.0}  # fmt: skip


def _tiny_png(folder) -> str:
    Image.new("RGB", (8, 6), (90, 40, 60)).save(folder / "view.png")
    return "view.png"


def _module_run(folder, path, format, replies, scorer):
    """A run of the ``queued`` backend answering ``replies``, made once a module in ``folder``
    (its tests read it, or write beside it)."""
    plugin = folder / "offline_plugin.py"
    shutil.copy(OFFLINE_PLUGIN, plugin)  # a config loads .py plugins only from its own folder or below
    config = {
        "plugins": [str(plugin.resolve())], "dataset": {"path": str(path), "format": format}, "backend": "queued",
        "strategy": "choice", "scorers": [scorer], "runs": 1, "concurrency": 1, "timeout": 5, "output": str(folder / f"run-{format}"),
    }  # fmt: skip
    (folder / f"{format}.yaml").write_text(yaml.safe_dump(config))
    return run_with_queued_replies(folder / f"{format}.yaml", replies)


def _values(metrics, metric: str) -> dict[str, float]:
    return {"overall": metrics.overall[metric].value, **{k: v[metric].value for k, v in (metrics.per_category or {}).items()}}


def _chosen(run_dir, scorer) -> list[str | None]:
    return [row.parse.choice if row.parse is not None else None for row in read_rows(run_dir / "results.jsonl")]


@pytest.fixture(scope="module")
def viewspatial_run_made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("viewspatial")
    image = _tiny_png(folder)
    # each question its own text: identical requests would share one cached reply
    records = [{"question_type": t, "image_path": [image], "question": f"Where is object {i}?", "answer": a,
                "choices": "A. right\nB. left\nC. front\nD. back"} for i, (t, a, _) in enumerate(VIEWSPATIAL)]  # fmt: skip
    (folder / "ViewSpatial-Bench.json").write_text(json.dumps(records))
    return _module_run(folder, folder / "ViewSpatial-Bench.json", "viewspatial", [r for *_, r in VIEWSPATIAL], "choice")


@pytest.fixture
def viewspatial_run(viewspatial_run_made, queued_backend):
    """The module's ViewSpatial run, read while a ``queued`` backend is registered (as when it ran)."""
    return viewspatial_run_made


def test_viewspatial_reads_each_reply_as_its_evaluate_py_does(viewspatial_run):
    assert _chosen(viewspatial_run.run_dir, "choice") == VIEWSPATIAL_LABELS


def test_viewspatial_accuracies_are_its_evaluate_py_s(viewspatial_run):
    assert _values(viewspatial_run.summary.metrics["choice"], "accuracy") == pytest.approx(VIEWSPATIAL_ACCURACY, abs=1e-12)


def _mindcube_lines(image: str) -> str:
    return "".join(json.dumps({"id": rid, "question": f"Which is ahead of view {i}? A. Sofa B. Lamp C. Window D. Door", "images": [image],
                               "gt_answer": gold}) + "\n" for i, (rid, gold, _) in enumerate(MINDCUBE))  # fmt: skip


@pytest.fixture(scope="module")
def mindcube_run_made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mindcube")
    image = _tiny_png(folder)
    (folder / "MindCube_tinybench.jsonl").write_text(_mindcube_lines(image))
    return _module_run(folder, folder / "MindCube_tinybench.jsonl", "mindcube", [r for *_, r in MINDCUBE], "choice-mindcube")


@pytest.fixture
def mindcube_run(mindcube_run_made, queued_backend):
    """The module's MindCube run, read while a ``queued`` backend is registered (as when it ran)."""
    return mindcube_run_made


def test_mindcube_reads_each_reply_as_its_evaluator_does(mindcube_run):
    assert _chosen(mindcube_run.run_dir, "choice-mindcube") == MINDCUBE_LABELS


def test_mindcube_accuracies_are_its_evaluator_s_translation_left_out_of_the_overall(mindcube_run):
    assert _values(mindcube_run.summary.metrics["choice-mindcube"], "accuracy") == pytest.approx(MINDCUBE_ACCURACY, abs=1e-12)
    assert mindcube_run.summary.metrics["choice-mindcube"].overall["accuracy"].n == 8


def test_mindcube_overall_counts_every_setting_when_the_scorer_is_told_so(tmp_path, offline_plugin_file, queued_backend):
    image = _tiny_png(tmp_path)
    (tmp_path / "MindCube_tinybench.jsonl").write_text(_mindcube_lines(image))
    config = {
        "plugins": [str(offline_plugin_file)], "dataset": {"path": str(tmp_path / "MindCube_tinybench.jsonl"), "format": "mindcube"},
        "backend": "queued", "strategy": "choice", "scorers": [{"name": "choice-mindcube", "options": {"overall_excludes": []}}],
        "runs": 1, "concurrency": 1, "timeout": 5, "output": str(tmp_path / "run-all"),
    }  # fmt: skip
    (tmp_path / "all.yaml").write_text(yaml.safe_dump(config))
    queued_backend.queue(*[r for *_, r in MINDCUBE])
    result = run_pipeline(load_pipeline(tmp_path / "all.yaml"))
    assert result.summary.metrics["choice-mindcube"].overall["accuracy"].value == pytest.approx(7 / 10)


@pytest.fixture(scope="module")
def srbench_run_made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("3dsrbench")
    image = _tiny_png(folder)
    lines = ["index\tqid\tquestion\tA\tB\tC\tD\tanswer\tcategory\timage"]
    for index, (qid, options, answer, category, _) in enumerate(SRBENCH):
        cells = [*options, "nan", "nan"][:4]
        lines.append("\t".join([str(index), qid, f"Which is higher ({index})?", *cells, answer, category, image]))
    (folder / "3DSRBench.tsv").write_text("\n".join(lines) + "\n")
    return _module_run(folder, folder / "3DSRBench.tsv", "3dsrbench", [r for *_, r in SRBENCH], "choice-3dsrbench")


@pytest.fixture
def srbench_run(srbench_run_made, queued_backend):
    """The module's 3DSRBench run, read while a ``queued`` backend is registered (as when it ran);
    its tests read it, or rescore it beside it."""
    return srbench_run_made


@pytest.mark.parametrize("metric", sorted(VLMEVALKIT))
def test_3dsrbench_gives_vlmevalkit_s_four_accuracies_overall_and_per_sub_category(srbench_run, metric):
    values = _values(srbench_run.summary.metrics["choice-3dsrbench"], metric)
    assert {k: v for k, v in values.items() if k not in VANILLA_PER_TYPE} == pytest.approx(VLMEVALKIT[metric], abs=1e-12)


def test_3dsrbench_gives_the_authors_circular_accuracy_per_type(srbench_run):
    values = _values(srbench_run.summary.metrics["choice-3dsrbench"], "circular_accuracy")
    assert {k: values[k] for k in AUTHORS_CIRCULAR_PER_TYPE} == pytest.approx(AUTHORS_CIRCULAR_PER_TYPE, abs=1e-12)


def test_3dsrbench_gives_each_type_s_vanilla_accuracy(srbench_run):
    values = _values(srbench_run.summary.metrics["choice-3dsrbench"], "vanilla_accuracy")
    assert {k: values[k] for k in VANILLA_PER_TYPE} == pytest.approx(VANILLA_PER_TYPE, abs=1e-12)


def test_3dsrbench_read_by_lmms_eval_s_rule_gives_lmms_eval_s_numbers(srbench_run):
    again = rescore_run(srbench_run.run_dir, "3dsrbench-lmms").summary.metrics["choice-3dsrbench"]
    assert {m: again.overall[m].value for m in LMMS_EVAL} == pytest.approx(LMMS_EVAL, abs=1e-12)
    assert {k: v for k, v in _values(again, "vanilla_accuracy").items() if k != "overall"} == pytest.approx(LMMS_EVAL_VANILLA, abs=1e-12)


def test_the_report_gives_mindcube_s_overall_with_translation_left_out(mindcube_run, tmp_path):
    from povagent.report.build import write_report

    write_report(mindcube_run.run_dir, tmp_path / "report", gallery=False, n_boot=200)
    (system,) = json.loads((tmp_path / "report" / "summary.json").read_text())["metrics"]["choice-mindcube"].values()
    reported = {"overall": system["overall"]["accuracy"]["value"], **{k: c["accuracy"]["value"] for k, c in system["per_category"].items()}}
    assert reported == pytest.approx(MINDCUBE_ACCURACY, abs=1e-12)
