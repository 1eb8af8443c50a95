"""Each set's official rule is the parser a choice pipeline on it gets when it names none; a
harness's rule is a labelled alternative the pipeline names."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline


@pytest.mark.parametrize(("format", "rule"), [
    ("viewspatial", "viewspatial-official"), ("mindcube", "mindcube-official"), ("3dsrbench", "vlmevalkit-exact"),
])  # fmt: skip
def test_a_choice_pipeline_naming_no_parser_reads_with_the_sets_own_rule(choice_pipeline, format, rule):
    assert load_pipeline(choice_pipeline(format)).parser.name == rule


@pytest.mark.parametrize(("format", "rule"), [("viewspatial", "viewspatial"), ("mindcube", "mindcube"), ("3dsrbench", "3dsrbench-lmms")])
def test_lmms_eval_s_port_is_an_alternative_the_pipeline_names(choice_pipeline, format, rule):
    path = choice_pipeline(format)
    path.write_text(yaml.safe_dump(yaml.safe_load(path.read_text()) | {"parser": rule}, sort_keys=False))
    assert load_pipeline(path).parser.name == rule


def test_a_parser_the_pipeline_names_wins_over_the_sets_rule(choice_pipeline):
    path = choice_pipeline("viewspatial")
    data = yaml.safe_load(path.read_text()) | {"parser": "vlmevalkit-exact"}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    assert load_pipeline(path).parser.name == "vlmevalkit-exact"
