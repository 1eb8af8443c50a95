"""VLMEvalKit's ``load`` step: every VLMEvalKit rule reads a reply pandas reads as missing as
``"nan"``, as VLMEvalKit's ``evaluate`` hands it over (``pd.read_csv`` / ``pd.read_excel``, then
``str()``); the set's own rules and lmms-eval's read the reply as written."""

from __future__ import annotations

import pytest

from povagent.answers.numeric_question import number_answer_schema
from povagent.answers.spec import AnswerSpec
from povagent_plugins.parsers.mcq.vlmevalkit_exact import vlmevalkit_exact_label
from povagent_plugins.parsers.mcq.vlmevalkit_load import PANDAS_MISSING, as_vlmevalkit_loads, options_as_vlmevalkit_loads
from povagent_plugins.parsers.mcq.vlmevalkit_spatial import spatial_bench_label

YES_NO = AnswerSpec(schema={}, asks_frame=False, choices=(("A", "yes"), ("B", "no")))
FOUR = AnswerSpec(schema={}, asks_frame=False, choices=(("A", "left"), ("B", "right"), ("C", "front"), ("D", "back")))
NUMBER = AnswerSpec(schema=number_answer_schema(), asks_frame=False)


def test_the_missing_values_are_pandas_own_defaults():
    parsers = pytest.importorskip("pandas._libs.parsers")
    assert frozenset(parsers.STR_NA_VALUES) == PANDAS_MISSING


@pytest.mark.parametrize("cell", sorted(PANDAS_MISSING))
def test_a_reply_pandas_reads_as_missing_is_nan(cell):
    assert as_vlmevalkit_loads(cell) == "nan"


@pytest.mark.parametrize("cell", [" N/A", "N/A ", "none", "NAN", "N/A.", "Null", "A", "nan\n"])
def test_a_reply_pandas_keeps_is_read_as_written(cell):
    assert as_vlmevalkit_loads(cell) == cell


@pytest.mark.parametrize("parser", ["vlmevalkit-spatial", "vlmevalkit-exact", "vlmevalkit-vsibench"])
def test_every_vlmevalkit_rule_reads_no_option_in_n_a_though_its_letter_rule_alone_reads_a(povagent_host, parser):
    assert spatial_bench_label("N/A") == "A"  # what the rule would read without pandas
    parse = povagent_host.parser(parser, {}).parse("N/A", FOUR)
    assert parse.choice is None and not parse.answered
    assert povagent_host.parser(parser, {}).parse(" N/A", FOUR).choice == ("A" if parser != "vlmevalkit-exact" else None)


def test_vlmevalkits_exact_rule_reads_no_option_text_in_none(povagent_host):
    assert vlmevalkit_exact_label("None", YES_NO.choices) == "B"  # "none" holds "no": what can_infer reads without pandas
    assert povagent_host.parser("vlmevalkit-exact", {}).parse("None", YES_NO).choice is None


def test_vlmevalkits_vsibench_rule_reads_no_number_in_an_empty_or_missing_reply(povagent_host):
    parser = povagent_host.parser("vlmevalkit-vsibench", {})
    assert parser.parse("NA", NUMBER).number is None
    assert parser.parse("3", NUMBER).number == 3.0


@pytest.mark.parametrize(("parser", "reads"), [("viewspatial-official", "A"), ("viewspatial", "A"), ("mmsi-official", "A")])
def test_the_sets_own_rules_and_lmms_evals_read_n_a_as_written(povagent_host, parser, reads):
    assert povagent_host.parser(parser, {}).parse("N/A", FOUR).choice == reads


def test_an_option_whose_text_pandas_reads_as_missing_is_no_choice_of_vlmevalkits_exact_rule(povagent_host):
    # build_choices @ e8e78f05 on the loaded row keeps {A: yes, B: no, D: left}: "C" is no choice, so Z
    spec = AnswerSpec(schema={}, asks_frame=False, choices=(("A", "yes"), ("B", "no"), ("C", "None"), ("D", "left")))
    assert vlmevalkit_exact_label("C", spec.choices) == "C"  # what can_infer reads with the cell kept
    parser = povagent_host.parser("vlmevalkit-exact", {})
    assert parser.parse("C", spec).choice is None
    assert parser.parse("D", spec).choice == "D"  # the options after it stay
    assert parser.parse("C", spec.model_copy(update={"choices": (("A", "yes"), ("B", "NA"), ("C", "left"))})).choice == "C"


def test_options_logged_without_their_text_stay_choices():
    assert options_as_vlmevalkit_loads((("A", ""), ("B", ""), ("C", "NA"))) == (("A", ""), ("B", ""))
