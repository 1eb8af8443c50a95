"""An oracle that points at the projected ground truth scores ~0 on a generated set."""

from __future__ import annotations

from povagent.dataset.loader import load_dataset
from povagent.scoring.normalized_l2 import project_ground_truth, score_point


def test_the_ground_truth_is_in_frame_in_nearly_every_observer_view(tiny_dataset):
    # the paper: 92.9%; a target on top of a tall anchor seen from close by can leave the frame
    instances = load_dataset(tiny_dataset.root).instances(conditions=["c"])
    shown = [project_ground_truth(inst.target, inst.observer_camera).in_frame for inst in instances]
    assert instances and sum(shown) >= 0.9 * len(shown)


def test_every_inferred_instance_has_an_exploration_frame_showing_the_ground_truth(tiny_dataset):
    for inst in load_dataset(tiny_dataset.root).instances(conditions=["a"]):
        assert any(project_ground_truth(inst.target, f.camera).in_frame for f in inst.frames), inst.id


def test_scoring_the_projected_ground_truth_pixel_gives_zero(tiny_dataset):
    dataset = load_dataset(tiny_dataset.root)
    errors = []
    for inst in dataset.instances():
        frames = inst.frames
        if inst.condition.uses_exploration_frames:
            frames = tuple(f for f in frames if project_ground_truth(inst.target, f.camera).in_frame)
        best = frames[0]
        gt = project_ground_truth(inst.target, best.camera)
        score = score_point(inst, best, gt.u * best.camera.width, gt.v * best.camera.height)
        errors.append(score.l2)
    assert errors and max(errors) < 1e-9


def test_the_oracle_backend_run_as_a_pipeline_scores_zero_on_a_generated_set(tiny_dataset, tmp_path):
    import yaml

    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    doc = {
        "dataset": str(tiny_dataset.root),
        "backend": "oracle",
        "strategy": "basic",
        "parser": "json",
        "scorers": ["official"],
        "cache": False,
        "output": str(tmp_path / "run"),
    }
    (tmp_path / "pipeline.yaml").write_text(yaml.safe_dump(doc))
    summary = run_pipeline(load_pipeline(tmp_path / "pipeline.yaml")).summary
    assert summary.overall.n_total == 3 * len(load_dataset(tiny_dataset.root).instances(conditions=["c"]))
    assert summary.overall.response_rate == 1.0
    for condition in ("a", "b", "c"):
        assert summary.per_condition[condition].mean_l2 < 1e-4, condition
