"""What a collected run holds: the numbers of each row, not its requests (read back when shown)."""

from __future__ import annotations

import tracemalloc

from povagent.dataset.instances import row_key
from povagent.report.collect import MAX_RAW_CHARS, collect, row_turns
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus

PROMPT = 50_000  # characters of one request: a CoT prompt with a long context


def long_prompt_run(folder, dataset, runs: int = 4):
    folder.mkdir()
    n = 0
    with ResultsWriter(folder / "results.jsonl") as w:
        for run in range(runs):
            for inst in dataset.instances():
                w.write(ResultRow(
                    key=row_key(inst.id, run), instance_id=inst.id, house_id=inst.house_id, pair_id=inst.pair_id,
                    direction=str(inst.direction), condition=str(inst.condition), run=run, backend="mock", strategy="basic",
                    status=RowStatus.ANSWERED, scores={"official": {"answered": True, "l2": 0.25, "gt_in_frame": True}},
                    exchanges=[ExchangeRecord(request_hash=str(n), prompt=f"request {n} " + "p" * PROMPT, raw=f'{{"x": {n}}}')],
                ))  # fmt: skip
                n += 1
    return folder, n


def test_a_collected_run_keeps_its_requests_in_the_results_file(tmp_path, mini_dataset):
    folder, n = long_prompt_run(tmp_path / "run", mini_dataset)
    collect(folder)  # the modules it imports the first time are not what it holds
    tracemalloc.start()
    try:
        collection = collect(folder)
        held, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(collection.observations) == n
    assert held < n * PROMPT / 4  # every request kept would be n * PROMPT characters


def test_a_shown_rows_transcript_is_read_back_whole(tmp_path, mini_dataset):
    folder, n = long_prompt_run(tmp_path / "run", mini_dataset, runs=1)
    last = collect(folder).observations[-1]
    (request, answer), = tuple(row_turns(last))
    assert request.startswith(f"request {n - 1} ") and len(request) == MAX_RAW_CHARS + 1
    assert answer == last.raw


def test_a_number_every_run_repeats_is_held_once(tmp_path, mini_dataset):
    folder, _ = long_prompt_run(tmp_path / "run", mini_dataset, runs=2)
    observations = collect(folder).observations
    assert observations[0].l2 == 0.25 and all(o.l2 is observations[0].l2 for o in observations)
