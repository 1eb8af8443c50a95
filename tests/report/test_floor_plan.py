"""The floor plan under the maps from above (povagent/report/floor_plan.py): a generated house's
own plan, and none for a set whose records cannot give one."""

from __future__ import annotations

import json

from povagent.report.floor_plan import house_plan

HOUSE = "train_house_00000"


def test_a_generated_house_gives_the_plan_its_generator_built(generated_release):
    from povagent.generate.floorplan import generate_floorplan
    from povagent.generate.house_pipeline import house_generators

    record = json.loads((generated_release / "artifacts" / HOUSE / "_generated.json").read_text())
    built = generate_floorplan(house_generators(record["options"]["seed"], record["index"])["plan"])
    assert house_plan(generated_release, HOUSE) == built and built.rooms and built.slabs


def test_a_release_without_generator_records_has_no_plan(mini_root):
    assert house_plan(mini_root, HOUSE) is None and house_plan(None, HOUSE) is None


def test_a_record_no_generator_wrote_draws_no_plan_and_raises_nothing(generated_release, tmp_path):
    folder = tmp_path / "set" / "artifacts" / HOUSE
    folder.mkdir(parents=True)
    record = json.loads((generated_release / "artifacts" / HOUSE / "_generated.json").read_text())
    record["options"]["seed"] = -1  # numpy refuses a negative seed
    (folder / "_generated.json").write_text(json.dumps(record))
    assert house_plan(tmp_path / "set", HOUSE) is None


def test_a_house_name_leading_out_of_the_dataset_has_no_plan(generated_release):
    assert house_plan(generated_release, "../../etc") is None
