"""The report never copies a key povagent knows onto its pages, even from an older run's rows."""

from __future__ import annotations

from povagent.report.build import write_report

KEY = "lab-key-7c1e5a9b3d2f"


def test_a_key_echoed_in_an_older_runs_answers_reaches_no_report_file(tmp_path, write_answered_run, monkeypatch):
    # Rows written before answers were redacted as they arrived: the report removes the key
    # the run's config names (api_key_env) from every answer text it shows.
    monkeypatch.setenv("REPORT_LAB_VAR", KEY)
    backend = {"name": "litellm", "options": {"model": "openai/echo", "api_key_env": "REPORT_LAB_VAR"}}
    answers = [
        ("train_house_00000/0/right/c", '{"x": 300, "y": 200} (you sent Bearer ' + KEY + ")"),
        ("train_house_00000/0/left/c", "no point here, Bearer " + KEY),
    ]
    run = write_answered_run(tmp_path / "run", answers, backend=backend)
    write_report(run, out=tmp_path / "report", n_boot=0)
    written = [p for p in (tmp_path / "report").rglob("*") if p.is_file()]
    assert any(p.name == "report.html" for p in written) and any(p.parent.name == "answers" for p in written)
    assert [str(p) for p in written if KEY.encode() in p.read_bytes()] == []
    assert any(b"[REDACTED]" in p.read_bytes() for p in written if p.parent.name == "answers")
