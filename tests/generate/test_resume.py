"""A generation can be stopped, resumed and extended: complete houses are kept byte for byte."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import DatasetError, GenerationError
from povagent.generate import PhysicalRulesJudge, generate_dataset

#: The options of the session's ``two_houses`` (tests/conftest.py), whose houses these tests
#: copy: a mismatch fails ``one_house`` naming the option.
SEED = 5
FRAMES = 1


def files(root: Path) -> dict[str, tuple[bytes, int]]:
    """Every file's bytes and mtime (ns) under ``root``'s houses."""
    return {p.relative_to(root).as_posix(): (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted((root / "artifacts").rglob("*")) if p.is_file()}


def copy_house(two_houses: Path, index: int, out: Path) -> None:
    """Copy house ``index`` of the dataset ``two_houses`` (complete, with its record) into ``out/artifacts``."""
    name = f"train_house_{index:05d}"
    (out / "artifacts").mkdir(parents=True, exist_ok=True)
    copy(two_houses / "artifacts" / name, out / "artifacts" / name)


@pytest.fixture(scope="module")
def one_house(two_houses, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished one-house dataset, copied by tests that change it: house 0 of the session's
    ``two_houses``, which a one-house run keeps (it writes only ``meta.json``)."""
    out = tmp_path_factory.mktemp("one_house") / "data"
    copy_house(two_houses.root, 0, out)
    report = generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False)
    assert (report.kept, report.generated) == (1, 0)
    return out


def copy(src: Path, dst: Path) -> Path:
    subprocess.run(["cp", "-a", str(src), str(dst)], check=True)  # -a keeps the mtimes
    return dst


@pytest.fixture(scope="module")
def extended(one_house, tmp_path_factory: pytest.TempPathFactory):
    """(folder, files before, report): a copy of ``one_house`` asked for two houses (made once:
    a house costs seconds; the tests only read the result or work on copies)."""
    out = copy(one_house, tmp_path_factory.mktemp("extended") / "data")
    before = files(out)
    report = generate_dataset(out, houses=2, seed=SEED, frames=FRAMES, progress=False)
    return out, before, report


def test_asking_for_more_houses_makes_only_the_new_ones_and_leaves_the_old_files_untouched(extended, two_houses):
    out, before, report = extended
    after = files(out)
    assert (report.kept, report.generated) == (1, 1)
    assert {name: after[name] for name in before} == before  # same bytes and mtimes
    new = {name: data for name, (data, _) in after.items() if name.startswith("artifacts/train_house_00001/")}
    assert new, "house 1 was not made"
    # the new house is the one a two-house run makes in one go
    assert new == {name: (two_houses.root / name).read_bytes() for name in new}
    assert json.loads((out / "meta.json").read_text())["counts"]["houses"] == 2


def test_running_the_same_command_again_makes_nothing(one_house, tmp_path):
    out = copy(one_house, tmp_path / "data")
    before = files(out)
    report = generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False)
    assert (report.kept, report.generated) == (1, 0)
    assert files(out) == before


class OtherJudge(PhysicalRulesJudge):
    name = "other-rules"


@pytest.mark.parametrize(
    ("change", "named"),
    [({"seed": SEED + 1}, "seed"), ({"frames": FRAMES + 1}, "frames"), ({"with_render": True}, "with_render"), ({"judge": OtherJudge()}, "judge")],
)
def test_other_options_over_an_existing_dataset_are_refused_naming_the_option(one_house, tmp_path, change, named):
    out = copy(one_house, tmp_path / "data")
    before = files(out)
    with pytest.raises(DatasetError) as info:
        generate_dataset(out, progress=False, **{"houses": 2, "seed": SEED, "frames": FRAMES, **change})
    assert f"was generated with {named} " in str(info.value)
    assert files(out) == before and (out / "meta.json").exists()


def test_fewer_houses_than_are_complete_is_refused(extended, tmp_path):
    out = copy(extended[0], tmp_path / "data")
    with pytest.raises(DatasetError, match="ask for at least 2 houses"):
        generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False)


def test_a_half_written_house_is_redone_and_a_complete_one_kept(one_house, tmp_path):
    out = copy(one_house, tmp_path / "data")
    kept = files(out)
    # what a killed run leaves: meta.json not yet rewritten, a staging folder, a house without its record
    (out / "meta.json").unlink()
    (out / ".partial/train_house_00001.dead").mkdir(parents=True)
    (out / ".partial/train_house_00001.dead/exploration_log.json").write_text("[")
    (out / "artifacts/train_house_00002/exploration_images").mkdir(parents=True)
    report = generate_dataset(out, houses=2, seed=SEED, frames=FRAMES, progress=False)
    assert (report.kept, report.generated) == (1, 1)
    assert not (out / ".partial").exists() and not (out / "artifacts/train_house_00002").exists()
    assert {name: files(out)[name] for name in kept} == kept
    assert json.loads((out / "artifacts/train_house_00001/exploration_log.json").read_text())


def failing_judge(index: int) -> str:
    """A plugin module registering the judge ``fails-on-house-INDEX``: it raises on that house."""
    return f"""
from povagent import hookimpl
from povagent.generate import PhysicalRulesJudge

class FailsOnOneHouse(PhysicalRulesJudge):
    def judge(self, request):
        if request.house.house_id == "train_house_{index:05d}":
            raise RuntimeError("this judge cannot judge house {index}")
        return super().judge(request)

@hookimpl
def register_judges(register):
    register("fails-on-house-{index}", FailsOnOneHouse, description="a test judge that raises on house {index}")
"""


def test_a_failing_house_is_named_while_the_others_finish_and_the_command_ends_non_zero(tmp_path):
    plugin = tmp_path / "failing_judge.py"
    plugin.write_text(failing_judge(0))
    out = tmp_path / "data"
    # in this process (--jobs 1), houses in index order: house 1 is made after house 0 failed.
    # The console script's test below fails a house in the worker pool
    args = ["generate", "--out", str(out), "--houses", "2", "--seed", str(SEED), "--frames", str(FRAMES), "--plugin", str(plugin),
            "--judge", "fails-on-house-0", "--jobs", "1"]
    result = CliRunner().invoke(app, args)
    assert isinstance(result.exception, GenerationError)
    message = str(result.exception)
    assert f"1 of 2 houses failed: house 0 (seed {SEED}): RuntimeError: this judge cannot judge house 0" in message
    assert "run the same command again to redo only the failed ones" in message
    assert [f.index for f in result.exception.failures] == [0]
    assert sorted(p.name for p in (out / "artifacts").iterdir()) == ["train_house_00001"]
    assert not (out / "meta.json").exists()


#: One child runs the console script's ``main`` once per command (one interpreter start and
#: import rather than one per command), with Dask made uninstallable (``sys.modules`` entries of
#: None) from its start; after each command it prints ``-- exit CODE --`` on stderr, and after the
#: last one ``-- loaded [...] --``: which of the house pipeline's libraries the child imported.
CONSOLE_CHILD = """
import json, sys
sys.modules['distributed'] = None; sys.modules['dask'] = None
from povagent.cli import main
for args in json.loads(sys.argv[1]):
    sys.argv = ['povagent', *args]
    try:
        main()
        code = 0
    except SystemExit as exc:
        code = exc.code
    print(f'-- exit {code} --', file=sys.stderr, flush=True)
heavy = ('povagent.generate.house_pipeline', 'povagent.generate.renderer', 'trimesh', 'scipy', 'embreex')
print('-- loaded ' + json.dumps([m for m in heavy if m in sys.modules]) + ' --', file=sys.stderr, flush=True)
"""


@pytest.fixture(scope="module")
def console_commands(two_houses, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, tuple[str, str, Path]], list[str]]:
    """(``{name: (exit code, stderr, out folder)}``, the libraries the child loaded) of three
    commands run by :data:`CONSOLE_CHILD`: ``no-dask`` asks for a cluster without Dask
    installed; ``validate`` checks the session's ``two_houses``; ``failing-house`` makes two
    houses with the default job count, so in a pool of worker processes (on a machine with two
    cores or more), with a judge that fails house 1. The first goes first: nothing of the last
    (its plugin) is loaded when it runs."""
    tmp = tmp_path_factory.mktemp("console")
    plugin = tmp / "failing_judge.py"
    plugin.write_text(failing_judge(1))
    commands = {
        "no-dask": ["generate", "--out", str(tmp / "no-dask"), "--houses", "1", "--cluster", "local:2"],
        "validate": ["validate", str(two_houses.root)],
        "failing-house": ["generate", "--out", str(tmp / "failing-house"), "--houses", "2", "--seed", str(SEED), "--frames", str(FRAMES),
                          "--plugin", str(plugin), "--judge", "fails-on-house-1"],
    }  # fmt: skip
    done = subprocess.run([sys.executable, "-c", CONSOLE_CHILD, json.dumps(list(commands.values()))], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    parts = re.split(r"^-- exit (\S+) --$", done.stderr, flags=re.MULTILINE)
    assert len(parts) == 2 * len(commands) + 1, done.stderr[-2000:]
    loaded = re.search(r"^-- loaded (.*) --$", parts[-1], flags=re.MULTILINE)
    assert loaded, done.stderr[-2000:]
    return {name: (parts[2 * i + 1], parts[2 * i], tmp / name) for i, name in enumerate(commands)}, json.loads(loaded.group(1))


def test_the_console_script_ends_non_zero_with_one_line_naming_the_failed_house(console_commands):
    """The failure crosses the worker pool's process boundary (see ``console_commands``)."""
    code, stderr, _ = console_commands[0]["failing-house"]
    assert code not in ("0", "None"), stderr
    assert stderr.strip().splitlines()[-1].startswith(f"error: 1 of 2 houses failed: house 1 (seed {SEED})"), stderr[-2000:]


def test_a_cluster_without_the_extra_is_one_line_naming_it_and_writes_nothing(console_commands):
    code, stderr, out = console_commands[0]["no-dask"]
    assert code == "2", stderr
    assert stderr.strip() == "error: Dask is not installed: --cluster needs the cluster extra, pip install 'povagent[cluster]'"
    assert not out.exists()


def test_validating_and_handing_houses_to_a_worker_pool_load_no_renderer(console_commands):
    """``validate`` reads the house records, and the process that hands houses to a pool writes
    them and ``meta.json``: neither makes a house, so neither pays for the mesh library, SciPy and
    Embree (about a second of CPU a process)."""
    from povagent.generate.dataset import default_jobs

    commands, loaded = console_commands
    code, stderr, _ = commands["validate"]
    assert code in ("0", "None"), stderr
    if default_jobs(2) < 2:
        pytest.skip("one core: the failing-house command made its houses in its own process")
    assert loaded == [], f"the child loaded {loaded}"


def test_a_staging_folder_recreated_after_another_run_cleared_it_is_never_placed(tmp_path):
    """A stale writer (its client killed) goes on writing after a re-run cleared ``.partial/``:
    its writes recreate the folder (``mkdir(parents=True)``), possibly on the same inode number,
    without the files it wrote first. That half house must not be renamed into place."""
    from povagent.generate.record import GenerationOptions, HouseSummary, clear_partial, house_folder, write_house_atomically

    out = tmp_path / "data"
    options = GenerationOptions(version="test", seed=0, frames=1, with_render=False, judge="physical-rules")

    def stale_write(folder: Path) -> HouseSummary:
        (folder / "first.png").write_bytes(b"written before the clear")
        clear_partial(out)  # another run starts and clears what it takes for leftovers
        (folder / "exploration_images").mkdir(parents=True)  # what write_png does next
        (folder / "exploration_images" / "frame_000.png").write_bytes(b"written after")
        return HouseSummary(0, "train_house_00000", 1, 1, 1, 1)

    with pytest.raises(RuntimeError, match="removed while the house was written"):
        write_house_atomically(out, 0, options, stale_write)
    assert not house_folder(out, 0).exists()
