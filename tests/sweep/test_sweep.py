"""Sweeps: expansion into cells, dry-run accounting, one shared cache, the sweep index."""

from __future__ import annotations

import json
import textwrap

import pytest
import yaml

from povagent.errors import ConfigError
from povagent.run.sweep import dry_run, expand_sweep, run_sweep

PER_CONDITION = 4


@pytest.fixture
def sweep_file(tmp_path, sweep_release, offline_plugin):
    base = {
        "plugins": [offline_plugin.__file__],
        "dataset": {"path": str(sweep_release)},
        "backend": {"name": "test-center"},
        "strategy": "test-point",
        "parser": "test-json",
        "concurrency": 4,
        "output": "ignored-by-sweeps",
    }
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(base))

    def make(body: str) -> object:
        path = tmp_path / "sweep.yaml"
        path.write_text(f"base: base.yaml\noutput: {tmp_path / 'sweep'}\n" + textwrap.dedent(body))
        return path

    return make


def test_axes_expand_into_the_cartesian_product_of_cells(sweep_file):
    _, cells = expand_sweep(sweep_file("axes:\n  backend: [test-center, test-flaky]\n  conditions: [a, c]\n  runs: [0, 1]\n"))
    assert [c.name for c in cells][:3] == ["test-center__a__run0", "test-center__a__run1", "test-center__c__run0"]
    assert len(cells) == 8
    cell = cells[-1]
    assert cell.axes == {"backend": "test-flaky", "conditions": "c", "runs": "run1"}
    assert cell.config.backend.name == "test-flaky" and cell.config.run_indices == [1]
    assert [c.value for c in cell.config.instances.conditions] == ["c"]
    assert cell.config.output.name == "test-flaky__c__run1"


def test_named_overrides_are_one_more_axis(sweep_file):
    _, cells = expand_sweep(sweep_file("overrides:\n  short: {strategy: {name: test-point, options: {max_tokens: 8}}}\n  long: {}\n"))
    assert [c.name for c in cells] == ["short", "long"]
    assert cells[0].config.strategy.options == {"max_tokens": 8} and cells[1].config.strategy.options == {}


def test_axis_value_replaces_the_base_component_with_its_options(sweep_file, tmp_path):
    base = yaml.safe_load((tmp_path / "base.yaml").read_text())
    base["backend"] = {"name": "test-center", "options": {"delay_s": 0.0}}
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(base))
    _, cells = expand_sweep(sweep_file("axes:\n  backend: [{name: test-flaky, options: {script: []}}]\n"))
    assert cells[0].config.backend.options == {"script": []}


def test_unknown_plugin_in_an_axis_names_the_sweep_line(sweep_file):
    path = sweep_file("axes:\n  strategy:\n    - test-point\n    - test-pont\n")
    with pytest.raises(ConfigError) as err:
        expand_sweep(path)
    assert f"{path}, line 6: axes.strategy[1]: unknown strategy 'test-pont' (did you mean 'test-point'?)" in str(err.value)


def test_typo_in_sweep_key_is_reported(sweep_file):
    path = sweep_file("axis:\n  runs: [0]\n")
    with pytest.raises(ConfigError, match=r"unknown key 'axis' in the top level \(did you mean 'axes'\?\)"):
        expand_sweep(path)


def test_sweep_writes_a_folder_per_cell_and_an_index(sweep_file, tmp_path):
    result = run_sweep(sweep_file("axes:\n  conditions: [a, b]\n"), quiet=True)
    index = json.loads((tmp_path / "sweep" / "sweep.json").read_text())
    assert [c["name"] for c in index["cells"]] == ["a", "b"]
    assert all(c["status"] == "done" and c["rows"]["answered"] == PER_CONDITION for c in index["cells"])
    for cell in result.cells:
        assert (cell.config.output / "results.jsonl").is_file() and (cell.config.output / "summary.json").is_file()


def test_rerunning_a_finished_sweep_makes_no_model_call(sweep_file, offline_plugin):
    path = sweep_file("axes:\n  conditions: [a, b]\n  runs: [0, 1]\n")
    run_sweep(path, quiet=True)
    calls = offline_plugin.CALLS["count"]
    assert calls == 4 * PER_CONDITION
    again = run_sweep(path, quiet=True)
    assert offline_plugin.CALLS["count"] == calls
    assert sum(r.stats.requests for r in again.results.values()) == 0


def test_cells_share_one_cache(sweep_file, offline_plugin, tmp_path):
    # Two named overrides that ask exactly the same thing: the second cell is all cache hits.
    result = run_sweep(sweep_file("overrides:\n  first: {}\n  second: {}\n"), quiet=True)
    assert offline_plugin.CALLS["count"] == 3 * PER_CONDITION
    assert result.results["second"].stats.cache_hits == 3 * PER_CONDITION
    assert (tmp_path / "sweep" / "cache.sqlite").is_file()


def test_dry_run_subtracts_finished_keys_and_estimates_tokens(sweep_file, offline_plugin):
    path = sweep_file("axes:\n  conditions: [a, c]\n")
    _, cells = expand_sweep(path)
    before = {c.name: c for c in dry_run(cells)}
    assert before["a"].requests == PER_CONDITION and before["a"].n_done == 0
    assert before["a"].prompt_tokens > before["c"].prompt_tokens > 0  # three frames vs one view
    assert before["a"].max_completion_tokens == 32 * PER_CONDITION
    run_sweep(path, quiet=True)
    assert offline_plugin.CALLS["count"] == 2 * PER_CONDITION
    after = {c.name: c for c in dry_run(cells)}
    assert after["a"].requests == 0 and after["a"].n_done == PER_CONDITION and after["a"].prompt_tokens == 0
    assert offline_plugin.CALLS["count"] == 2 * PER_CONDITION  # a dry run calls nothing


def test_a_cell_folder_planted_as_a_link_is_refused_before_any_cell_runs(sweep_file, tmp_path, offline_plugin):
    import os

    from povagent.errors import WriteTargetError

    path = sweep_file("axes:\n  conditions: [a, b]\n")
    run_sweep(path, quiet=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    cell = tmp_path / "sweep" / "b"
    os.rename(cell, tmp_path / "b-moved")
    os.symlink(elsewhere, cell)  # an empty folder elsewhere, which a run would take as new
    with pytest.raises(WriteTargetError, match=r"sweep/b: is a symbolic link"):
        run_sweep(path, quiet=True)
    assert list(elsewhere.iterdir()) == []
