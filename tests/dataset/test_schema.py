"""The shipped JSON Schemas are exactly what the models generate."""

from __future__ import annotations

from importlib import resources

import pytest

from povagent.dataset.schema import SCHEMA_TYPES, schema_text, validator


@pytest.mark.parametrize("name", sorted(SCHEMA_TYPES))
def test_shipped_schema_matches_the_models(name):
    shipped = resources.files("povagent").joinpath("schemas", f"{name}.schema.json").read_text()
    assert shipped == schema_text(name), "run: python -m povagent.dataset.schema"


def test_schema_accepts_a_sentence_as_string_or_object():
    v = validator("pair_file")
    errors = [e for e in v.iter_errors([{"stage6": {"up": {"type_c": {"sentence": "x"}}}}]) if "stage6" in list(e.absolute_path)]
    assert errors == []
