"""Resume rules: which keys a run still owes, and how failed keys are re-attempted.

A key is ``instance id#run``. A run folder's rows say which keys are done; the last row of a key
wins; a key whose last row is an infrastructure failure is pending again (by default), while a
parse error is an answer and stays done; rows of another pipeline are refused. Pending keys come
house by house, each house's exploration-frame (A/B) keys before its Given keys. Re-attempting
drops the failed keys' rows from the file, keeping every other complete line byte for byte.
"""

from __future__ import annotations

import pytest

from povagent.config.models import PipelineConfig
from povagent.dataset.instances import row_key
from povagent.errors import ConfigError
from povagent.results.rows import ResultRow, ResultsWriter, RowStatus
from povagent.run.journal import drop_rows
from povagent.run.pending import RESULTS, house_major, pending_keys, plan_keys, select_instances


@pytest.fixture
def config(mini_root, tmp_path):
    return PipelineConfig(dataset={"path": str(mini_root)}, model="openai/test", output=tmp_path / "run", runs=2)


def row(key: str, status: RowStatus, config: PipelineConfig, config_hash: str | None = None) -> ResultRow:
    iid = key.split("#")[0]
    house, pair, direction, condition = iid.split("/")
    return ResultRow(key=key, instance_id=iid, house_id=house, pair_id=pair, direction=direction, condition=condition,
                     status=status, config_hash=config.config_hash() if config_hash is None else config_hash)


def write(config: PipelineConfig, *rows: ResultRow) -> None:
    with ResultsWriter(config.output / RESULTS) as w:
        for r in rows:
            w.write(r)


def test_a_fresh_folder_owes_every_instance_and_run(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    plan = plan_keys(config, instances)
    assert plan.n_total == 2 * len(instances)
    assert len(plan.pending) == plan.n_total and not plan.done and not plan.failed


def test_answered_and_parse_error_keys_are_done(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    a, b = instances[0].id, instances[1].id
    write(config, row(row_key(a, 0), RowStatus.ANSWERED, config), row(row_key(b, 1), RowStatus.PARSE_ERROR, config))
    plan = plan_keys(config, instances)
    assert plan.done == {row_key(a, 0), row_key(b, 1)}
    assert (instances[0], 0) not in plan.pending and (instances[1], 1) not in plan.pending
    assert len(plan.pending) == plan.n_total - 2


def test_an_infra_error_is_pending_again_by_default(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    key = row_key(instances[0].id, 0)
    write(config, row(key, RowStatus.INFRA_ERROR, config))
    plan = plan_keys(config, instances)
    assert plan.failed == {key} and key not in plan.done
    assert (instances[0], 0) in plan.pending
    kept = plan_keys(config, instances, retry_failed=False)
    assert key in kept.done and (instances[0], 0) not in kept.pending


def test_the_last_row_of_a_key_decides(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    key = row_key(instances[0].id, 0)
    write(config, row(key, RowStatus.INFRA_ERROR, config), row(key, RowStatus.ANSWERED, config))
    plan = plan_keys(config, instances)
    assert key in plan.done and not plan.failed
    write(config, row(key, RowStatus.INFRA_ERROR, config))
    assert plan_keys(config, instances).failed == {key}


def test_rows_of_keys_outside_the_pipeline_are_ignored(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    wanted = row_key(instances[1].id, 0)
    write(config, row(row_key(instances[0].id, 7), RowStatus.ANSWERED, config), row(wanted, RowStatus.ANSWERED, config))
    plan = plan_keys(config, instances)
    assert plan.done == {wanted} and len(plan.pending) == plan.n_total - 1


@pytest.mark.parametrize("other_hash", ["0000000000000000", "ffffffffffffffff"])
def test_rows_of_another_pipeline_are_refused(config, mini_dataset, other_hash):
    instances = select_instances(mini_dataset, config)
    write(config, row(row_key(instances[0].id, 0), RowStatus.ANSWERED, config, config_hash=other_hash))
    with pytest.raises(ConfigError, match="different pipeline"):
        plan_keys(config, instances)


def test_dry_runs_plan_as_a_run_does(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    write(config, row(row_key(instances[0].id, 0), RowStatus.ANSWERED, config),
          row(row_key(instances[1].id, 0), RowStatus.INFRA_ERROR, config))
    n_total, n_done, pending = pending_keys(config, mini_dataset)
    plan = plan_keys(config, instances)
    assert (n_total, n_done, pending) == (plan.n_total, len(plan.done), plan.pending)
    assert n_done == 1
    assert pending_keys(config, mini_dataset, retry_failed=False)[1] == 2


def test_pending_keys_come_house_by_house_exploration_frames_first(config, mini_dataset):
    instances = select_instances(mini_dataset, config)
    order = house_major([(i, 0) for i in reversed(instances)])
    houses = [i.house_id for i, _ in order]
    assert houses == sorted(houses, key=houses.index)  # each house's keys together
    for house in set(houses):
        flags = [i.condition.uses_exploration_frames for i, _ in order if i.house_id == house]
        assert flags == sorted(flags, reverse=True)  # A/B before C
    assert house_major([]) == []


def test_instances_are_filtered_sampled_then_limited(config, mini_dataset):
    everything = select_instances(mini_dataset, config)
    given = select_instances(mini_dataset, config.model_copy(update={"instances": config.instances.model_copy(update={"conditions": ["c"]})}))
    assert given and all(str(i.condition) == "c" for i in given)
    limited = config.model_copy(update={"instances": config.instances.model_copy(update={"limit": 3})})
    assert select_instances(mini_dataset, limited) == everything[:3]
    sampled = config.model_copy(update={"instances": config.instances.model_copy(update={"sample": 4, "seed": 1})})
    picked = select_instances(mini_dataset, sampled)
    assert len(picked) == 4 and picked == [i for i in everything if i in picked]
    assert select_instances(mini_dataset, sampled) == picked
    whole = config.model_copy(update={"instances": config.instances.model_copy(update={"sample": len(everything)})})
    assert select_instances(mini_dataset, whole) == everything
    more = config.model_copy(update={"instances": config.instances.model_copy(update={"sample": len(everything) + 5})})
    assert select_instances(mini_dataset, more) == everything


def test_an_unknown_house_is_refused(config, mini_dataset):
    bad = config.model_copy(update={"instances": config.instances.model_copy(update={"houses": ["train_house_99999"]})})
    with pytest.raises(ConfigError, match="train_house_99999"):
        select_instances(mini_dataset, bad)


def test_dropping_rows_keeps_every_other_line_byte_for_byte(tmp_path):
    path = tmp_path / "results.jsonl"
    keep1 = '{"key": "a#0", "odd spacing":  1}\n'
    drop = '{"key":"b#0"}\n'
    keep2 = "not json at all\n"
    keep3 = '{"key": "c#0"}\n'
    path.write_text(keep1 + drop + keep2 + drop + keep3 + '{"key": "d#0"', encoding="utf-8")
    drop_rows(path, {"b#0"})
    assert path.read_text(encoding="utf-8") == keep1 + keep2 + keep3
    assert not path.with_suffix(".jsonl.tmp").exists()


def test_a_key_is_read_not_searched_for(tmp_path):
    path = tmp_path / "results.jsonl"
    text = '{"key": "x#0", "raw": "\\"key\\":\\"b#0\\""}\n["b#0"]\n'
    path.write_text(text, encoding="utf-8")
    drop_rows(path, {"b#0"})
    assert path.read_text(encoding="utf-8") == text


def test_dropped_rows_are_fsynced_then_renamed_in_with_the_folder_fsynced(tmp_path, monkeypatch):
    import os
    import stat

    kinds: list[str] = []
    real = os.fsync

    def spy(fd: int) -> None:
        kinds.append("folder" if stat.S_ISDIR(os.fstat(fd).st_mode) else "file")
        real(fd)

    path = tmp_path / "results.jsonl"
    path.write_text('{"key": "a#0"}\n{"key": "b#0"}\n', encoding="utf-8")
    monkeypatch.setattr(os, "fsync", spy)
    drop_rows(path, {"b#0"})
    assert kinds == ["file", "folder"]  # a power cut after the rename keeps the new file
    assert path.read_text(encoding="utf-8") == '{"key": "a#0"}\n'
