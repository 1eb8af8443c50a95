"""Reading VLMEvalKit's prediction files: the .tsv pandas writes with every cell quoted, the .xlsx
sheet, the option columns each dataset has, and a file treated as untrusted."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import pytest

from povagent.errors import PredictionsError
from povagent.results.vlmevalkit_log import read_vlmevalkit_predictions

HEADER = ["index", "question", "A", "B", "C", "D", "answer", "category", "qid", "prediction"]


def tsv(tmp_path: Path, rows: list[list[object]], header: list[str] = HEADER) -> Path:
    """A .tsv as VLMEvalKit's dump writes it (pandas to_csv, sep tab, csv.QUOTE_ALL)."""
    path = tmp_path / "Model_3DSRBench.tsv"
    with path.open("w", encoding="utf-8", newline="") as out:
        writer = csv.writer(out, delimiter="\t", quoting=csv.QUOTE_ALL, lineterminator="\n")
        writer.writerow(header)
        writer.writerows([[("" if c is None else c) for c in row] for row in rows])
    return path


def row(index: int = 0, prediction: object = "The answer is B.", answer: str = "B", qid: str = "VIN6MS3J") -> list[object]:
    return [index, "Is the car left of the tree?", "yes", "no", None, None, answer, "location_next_to", qid, prediction]


def test_a_row_gives_reply_gold_options_category_and_question_id(tmp_path):
    [reply] = read_vlmevalkit_predictions(tsv(tmp_path, [row(4, qid="VIN6MS3J-flip")])).replies
    assert (reply.item, reply.where, reply.reply, reply.gold) == ("4", "row 2", "The answer is B.", "B")
    assert reply.options == (("A", "yes"), ("B", "no"))  # empty option cells (pandas' NaN) end the options
    assert (reply.category, reply.question_id) == ("location_next_to", "VIN6MS3J-flip")


def test_a_quoted_prediction_keeps_its_tabs_newlines_and_quotes(tmp_path):
    text = 'Step 1:\tlook "left".\n\nAnswer: B'
    [reply] = read_vlmevalkit_predictions(tsv(tmp_path, [row(0, prediction=text), row(1)])).replies[:1]
    assert reply.reply == text


def test_viewspatial_candidates_give_the_options_as_lines_or_a_list(tmp_path):
    header = ["index", "question", "candidates", "answer", "question_type", "prediction"]
    rows = [[0, "q", "A. right\nB. left", "A. right", "Camera perspective - Relative Direction", "A"],
            [1, "q", "['A. front', 'B. back', 'C. left']", "C. left", "Person perspective - Relative Direction", "C"],
            [2, "q", "['front', 'back']", "B", "Person perspective - Relative Direction", "B"]]  # fmt: skip
    replies = read_vlmevalkit_predictions(tsv(tmp_path, rows, header)).replies
    assert [r.options for r in replies] == [
        (("A", "right"), ("B", "left")), (("A", "front"), ("B", "back"), ("C", "left")), (("A", "front"), ("B", "back"))
    ]
    assert replies[0].category == "Camera perspective - Relative Direction"  # question_type: how VLMEvalKit groups the set


VSI_HEADER = ["index", "video", "question", "candidates", "answer", "question_type", "prediction"]


def test_a_vsibench_row_with_no_candidates_and_a_number_as_answer_is_a_numerical_question(tmp_path):
    rows = [[0, "scannet/scene0011_00.mp4", "How many chair(s) are in this room?", None, "4", "object_counting", "four"],
            [1, "scannet/scene0011_00.mp4", "Which is closer?", "['A. sofa', 'B. lamp']", "B", "object_rel_distance", "B"]]  # fmt: skip
    numerical, choice = read_vlmevalkit_predictions(tsv(tmp_path, rows, VSI_HEADER)).replies
    assert (numerical.gold_number, numerical.gold, numerical.options, numerical.category) == (4.0, "4", (), "object_counting")
    assert (choice.gold_number, choice.gold, choice.options) == (None, "B", (("A", "sofa"), ("B", "lamp")))


@pytest.mark.parametrize(
    ("candidates", "answer", "message"),
    [(None, "about four", "'about four' is neither an option label A-Z nor a number (the row lists no options)"),
     ("['A. sofa', 'B. lamp']", "4", "'4' names no option label A-Z")],  # options listed: the gold must be one of them
)  # fmt: skip
def test_a_vsibench_row_whose_answer_is_neither_is_named_and_left_out(tmp_path, candidates, answer, message):
    path = tsv(tmp_path, [[0, "v.mp4", "q", candidates, answer, "object_counting", "4"]], VSI_HEADER)
    log = read_vlmevalkit_predictions(path)
    assert (log.replies, [str(p) for p in log.problems]) == ([], [f"{path}: row 2.answer: {message}; row left out"])


def test_a_list_cell_is_read_as_a_literal_and_never_run(tmp_path):
    header = ["index", "candidates", "answer", "prediction"]
    rows = [[0, "[__import__('os').system('touch ran')]", "A", "A"]]
    [reply] = read_vlmevalkit_predictions(tsv(tmp_path, rows, header)).replies
    assert reply.options == (("A", ""), ("B", ""), ("C", ""), ("D", ""))  # no options read: labels A-D
    assert not (Path.cwd() / "ran").exists()


def test_the_xlsx_sheet_reads_as_the_tsv_does(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")  # the test extra installs it
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(HEADER)
    sheet.append(row(0))
    sheet.append([1, "q", "yes", "no", None, None, "A", "height_higher", "Q2", 7])  # a number as the reply: VLMEvalKit's str()
    path = tmp_path / "Model_3DSRBench.xlsx"
    book.save(path)
    replies = read_vlmevalkit_predictions(path).replies
    assert [(r.item, r.reply, r.gold) for r in replies] == [("0", "The answer is B.", "B"), ("1", "7", "A")]
    assert replies == read_vlmevalkit_predictions(tsv(tmp_path, [row(0), [1, "q", "yes", "no", None, None, "A", "height_higher", "Q2", 7]])).replies


def test_an_xlsx_without_openpyxl_names_the_extra_to_install(tmp_path, monkeypatch):
    path = tmp_path / "Model_MindCubeBench.xlsx"
    path.write_bytes(b"PK\x03\x04" + b"\0" * 100)
    monkeypatch.setitem(sys.modules, "openpyxl", None)
    with pytest.raises(PredictionsError, match=r"reading an .xlsx file needs openpyxl: pip install 'povagent\[xlsx\]'"):
        read_vlmevalkit_predictions(path)


def test_a_damaged_xlsx_is_one_line(tmp_path):
    pytest.importorskip("openpyxl")
    path = tmp_path / "Model_MindCubeBench.xlsx"
    path.write_bytes(b"PK\x03\x04" + b"\0" * 100)
    with pytest.raises(PredictionsError, match="not an xlsx file"):
        read_vlmevalkit_predictions(path)


def test_an_xlsx_unpacking_past_the_bound_is_refused_before_it_is_parsed(tmp_path, monkeypatch):
    import zipfile

    import povagent.results.vlmevalkit_log as module

    path = tmp_path / "bomb.xlsx"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as packed:
        packed.writestr("xl/worksheets/sheet1.xml", b" " * 1_000_000)
    monkeypatch.setattr(module, "MAX_XLSX_UNPACKED", 100_000)
    with pytest.raises(PredictionsError, match="unpacks to 1000000 bytes"):
        read_vlmevalkit_predictions(path)


def test_a_file_split_by_split_think_says_so_in_a_note(tmp_path):
    header = ["index", "answer", "prediction", "thinking"]
    log = read_vlmevalkit_predictions(tsv(tmp_path, [[0, "A", "A", "The lamp is right, so A."], [1, "B", "B", ""]], header))
    assert len(log.replies) == 2
    assert log.notes == ["rows keeping reasoning in a thinking column: 1 (VLMEvalKit's SPLIT_THINK); prediction, what every rule reads here, "
                         "is the text after </think>, so a rule that reads the whole reply as written sees less than it would"]  # fmt: skip


def test_a_file_without_the_prediction_column_is_refused_naming_it(tmp_path):
    path = tsv(tmp_path, [[0, "B"]], ["index", "answer"])
    with pytest.raises(PredictionsError, match=r"row 1: no column prediction"):
        read_vlmevalkit_predictions(path)


@pytest.mark.parametrize(
    ("bad", "where", "message"),
    [
        (row(None), "row 3.index", "required, the row's index (at most 200 characters); row left out"),
        (row(9, answer="unknown"), "row 3.answer", "'unknown' names no option label A-Z; row left out"),
        (row(9, answer="C"), "row 3.answer", "the gold label 'C' is not among the row's options (A, B); row left out"),
        (row(0), "row 3.index", "'0' is used by an earlier row; this one left out"),
    ],
)
def test_a_bad_row_is_one_problem_naming_file_row_and_column_and_the_rest_are_read(tmp_path, bad, where, message):
    path = tsv(tmp_path, [row(0), bad, row(1)])
    log = read_vlmevalkit_predictions(path)
    assert [r.item for r in log.replies] == ["0", "1"]
    assert [str(p) for p in log.problems] == [f"{path}: {where}: {message}"]


def test_a_prediction_longer_than_a_parser_reads_is_a_bad_row_not_a_crash(tmp_path):
    log = read_vlmevalkit_predictions(tsv(tmp_path, [row(0, prediction="B" * 2_000_000), row(1)]))
    assert [r.item for r in log.replies] == ["1"]
    assert log.problems[0].json_path == "row 2.prediction"


def test_a_tsv_that_is_not_utf8_is_refused_in_one_line(tmp_path):
    path = tmp_path / "x.tsv"
    path.write_bytes(b'"index"\t"answer"\t"prediction"\n"0"\t"A"\t"\xff"\n')
    with pytest.raises(PredictionsError, match="is not UTF-8"):
        read_vlmevalkit_predictions(path)


def test_omnispatialbench_groups_by_sub_task_type_within_task_type(tmp_path):
    header = ["index", "question", "A", "B", "answer", "task_type", "sub_task_type", "prediction"]
    file = tsv(tmp_path, [[0, "Where is the bench?", "left", "right", "B", "Perspective_Taking", "Egocentric", "Answer: B"]], header)
    [reply] = read_vlmevalkit_predictions(file).replies
    assert (reply.category, reply.main_category, reply.options) == ("Egocentric", "Perspective_Taking", (("A", "left"), ("B", "right")))


def test_options_inside_the_question_are_read_where_the_row_has_no_option_columns(tmp_path):
    # the MMSI-Bench authors' table: the options live in the question, as in the set's Parquet file
    header = ["index", "question", "answer", "category", "prediction"]
    file = tsv(tmp_path, [[0, "Which way did the camera turn?\nOptions: A: Left, B: Right, C: Back, D: None", "C", "Motion-Cam", "``C``"]], header)
    [reply] = read_vlmevalkit_predictions(file).replies
    assert reply.options == (("A", "Left"), ("B", "Right"), ("C", "Back"), ("D", "None"))
