"""Any text in a sentence or a model answer reaches the report page exactly, and data the page
cannot read is said on the page, in headless Chromium.

The page embeds its gallery data as JSON in a ``<script>`` element and loads raw answers from
``answers/*.js`` files: markup in the text (``<!--``, ``</script>``, ``<script``, ``&``) and the
line separators U+2028/U+2029 are written as JSON ``\\u`` escapes, so HTML never reads them and
JSON gives them back. ``<!--`` used to become ``<\\!--``, an invalid escape: 0 cards, no error.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import pytest
import yaml
from test_report_html import VIEWER_SETTLED, body_attr, cards, dump  # the Chromium helpers

from povagent.report.build import write_report
from povagent.report.html import script_json
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus

pytestmark = pytest.mark.timeout(300)

#: One hostile text per card (its sentence); every raw answer holds all of them.
HOSTILE = [
    "the cup <!-- behind the sofa",
    "</script><script>document.body.dataset.pwned = 1</script>",
    "<script src=x>",
    "line\u2028separator and paragraph\u2029separator",
    "Tom & Jerry &amp; &lt;b&gt; <b>bold</b>",
    "--> ]]> <![CDATA[ <!-- <script>",
    "\\u003c an escape written out, and a quote \" and a backslash \\",
    "😀 中文 é <\u2028!-->",
]
RAW = " | ".join(HOSTILE)
INSTANCES = [f"train_house_00000/0/{d}/{c}" for d in ("right", "left", "front", "up") for c in ("a", "c")]


@pytest.fixture(scope="module")
def hostile_report(tmp_path_factory, mini_root):
    run = tmp_path_factory.mktemp("hostile") / "run"
    run.mkdir()
    (run / "config.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)}, "backend": {"name": "center", "options": {}},
        "strategy": {"name": "basic", "options": {}}, "parser": {"name": "json", "options": {}},
        "scorers": [{"name": "official", "options": {}}], "output": str(run),
    }))  # fmt: skip
    with ResultsWriter(run / "results.jsonl") as w:
        for text, iid in zip(HOSTILE, INSTANCES, strict=True):
            house, pair, direction, cond = iid.split("/")
            w.write(ResultRow(key=f"{iid}#0", instance_id=iid, house_id=house, pair_id=pair, direction=direction,
                              condition=cond, sentence=text, status=RowStatus.PARSE_ERROR, parser="json",
                              exchanges=[ExchangeRecord(request_hash="h", raw=RAW)]))  # fmt: skip
    return write_report(run, run / "report", n_boot=0)


def sentences(dom: str) -> list[str]:
    """The sentence each rendered card shows, as text."""
    grid = dom.split('<div id="gallery">', 1)[1].split("<script", 1)[0]  # not the script's own text
    return [html.unescape(s) for s in re.findall(r'<div class="sent">(.*?)</div>', grid, re.S)]


@pytest.mark.parametrize("text", HOSTILE)
def test_script_json_reads_back_as_the_text_and_holds_no_markup_character(text):
    embedded = script_json({"t": text})
    assert json.loads(embedded) == {"t": text}
    assert not set(embedded) & set("<>&\u2028\u2029")


def test_every_card_shows_its_sentence_exactly_in_the_browser(hostile_report, browser):
    dom = dump(browser, hostile_report.page)
    assert body_attr(dom, "data-gallery-count") == len(HOSTILE)
    assert len(cards(dom)) == len(HOSTILE)
    assert sorted(sentences(dom)) == sorted(HOSTILE)
    assert "data-pwned" not in dom  # nothing in the text ran
    assert re.search(r'<div id="data-error" role="alert" hidden', dom)  # no error banner


def test_the_raw_answer_reads_back_exactly_from_its_answers_file(hostile_report, browser):
    assert list((hostile_report.out / "answers").glob("*.js"))  # the answer is in a file, not the page
    dom = dump(browser, hostile_report.page, state="open=0", until=VIEWER_SETTLED)
    shown = re.search(r'<pre class="raw">(.*?)</pre>', dom, re.S)
    assert shown is not None, "the viewer shows no raw answer"
    assert html.unescape(shown.group(1)) == RAW
    assert "data-pwned" not in dom


def _copy(report, tmp_path: Path) -> Path:
    import shutil

    out = tmp_path / "copy"
    shutil.copytree(report.out, out)
    return out / report.page.name


def test_gallery_data_that_cannot_be_read_shows_a_visible_error(hostile_report, tmp_path, browser):
    page = _copy(hostile_report, tmp_path)
    text = page.read_text(encoding="utf-8")
    start = text.index('<script type="application/json" id="gallery-data">') + len('<script type="application/json" id="gallery-data">')
    page.write_text(text[:start] + '{"entries": [' + text[start + 1 :], encoding="utf-8")  # not JSON any more
    dom = dump(browser, page)
    banner = re.search(r'<div id="data-error" role="alert"( hidden="")?>(.*?)</div>', dom, re.S)
    assert banner is not None and banner.group(1) is None, "the error banner is not shown"
    assert "gallery data cannot be read" in banner.group(2)
    assert body_attr(dom, "data-data-error") == 1


def test_an_answers_file_that_cannot_be_read_shows_a_visible_error(hostile_report, tmp_path, browser):
    page = _copy(hostile_report, tmp_path)
    for f in (page.parent / "answers").glob("*.js"):
        f.write_text(f.read_text(encoding="utf-8")[:50], encoding="utf-8")  # cut: a syntax error
    dom = dump(browser, page, state="open=0", until=VIEWER_SETTLED)
    banner = re.search(r'<div id="data-error" role="alert"( hidden="")?>(.*?)</div>', dom, re.S)
    assert banner is not None and banner.group(1) is None, "the error banner is not shown"
    assert "answers file" in banner.group(2) and "cannot be read" in banner.group(2)
