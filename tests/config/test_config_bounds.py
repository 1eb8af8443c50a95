"""What a config may ask for is bounded, and every refusal is a clear message naming the file.

A YAML file is input like any other: a "billion laughs" of aliases, nesting 20,000 deep, a
binary or non-UTF-8 file, a 10 MB value, duplicate keys, ``runs: 100000000``, an infinite
retry wait, or an ``output:`` that is a file must each end in a :class:`ConfigError` naming the
file (and the line where there is one), never a traceback, a hang or an exhausted memory.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time

import pytest

from povagent.config.pipeline import load_pipeline, load_sweep
from povagent.errors import ConfigError

MAX_RUNS = 100  # repeats a pipeline may ask for (the paper averages 3)

GOOD = """\
dataset: {path: data/povbench}
backend: {name: center}
strategy: basic
parser: json
output: runs/x
"""


def write(tmp_path, text: str, name: str = "pipeline.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def refusal(path, loader=load_pipeline) -> str:
    with pytest.raises(ConfigError) as err:
        loader(path)
    message = str(err.value)
    assert str(path) in message, message
    return message


def billion_laughs(levels: int = 9, width: int = 9) -> str:
    lines = ['x-bomb: &l0 "lol"']
    for i in range(1, levels + 1):
        lines.append(f"x-l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * width) + "]")
    return "\n".join(lines) + "\n"


# -- aliases ------------------------------------------------------------------------------------
def test_a_billion_laughs_is_refused_without_exhausting_memory(tmp_path):
    # In a child process capped at 1 GiB: expanding 9**9 aliases would need far more.
    path = write(tmp_path, GOOD + billion_laughs())
    code = textwrap.dedent(f"""
        import resource, sys
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
        from povagent.config.pipeline import load_pipeline
        from povagent.errors import ConfigError
        try:
            load_pipeline({str(path)!r})
        except ConfigError as exc:
            print(exc)
            sys.exit(3)
    """)
    started = time.monotonic()
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert child.returncode == 3, child.stderr[-2000:]
    assert str(path) in child.stdout and "alias" in child.stdout
    assert time.monotonic() - started < 30


def test_laughs_inside_a_used_key_are_refused_too(tmp_path):
    # anchors first (an alias needs its anchor above it), then the pipeline using the last one
    text = billion_laughs(levels=6, width=10) + GOOD.replace("backend: {name: center}", "backend: {name: center, options: {extra: {k: *l6}}}")
    message = refusal(write(tmp_path, text))
    assert "alias" in message and "line" in message


def test_a_few_aliases_are_fine(tmp_path):
    path = write(tmp_path, GOOD.replace("dataset: {path: data/povbench}", "dataset: {path: &p data/povbench}") + "cache: *p\n")
    assert str(load_pipeline(path).cache.path) == "data/povbench"


def test_a_recursive_alias_is_refused(tmp_path):
    message = refusal(write(tmp_path, GOOD + "x-loop: &loop [1, *loop]\n"))
    assert "alias" in message and "line 6" in message


# -- nesting, size, encoding ------------------------------------------------------------------------
@pytest.mark.parametrize("style", ["flow", "block"])
def test_deep_nesting_is_a_clear_error(tmp_path, style):
    # 20,000 deep in flow style (the attack); block style grows quadratically, so 500 deep
    # (250 KB) stands for it while staying under the size bound
    deep = "[" * 20000 + "]" * 20000 if style == "flow" else "".join("  " * i + f"k{i}:\n" for i in range(500))
    text = GOOD + "x-deep: " + deep + "\n" if style == "flow" else GOOD + "x-deep:\n" + textwrap.indent(deep, "  ")
    message = refusal(write(tmp_path, text))
    assert "nest" in message and "line" in message


def test_a_file_larger_than_the_bound_is_refused_before_parsing(tmp_path):
    path = write(tmp_path, GOOD + "x-big: '" + "a" * (10 * 1024 * 1024) + "'\n")
    started = time.monotonic()
    message = refusal(path)
    assert time.monotonic() - started < 5
    assert len(message) < 1000 and "1 MiB" in message


def test_a_long_value_is_not_echoed_in_full(tmp_path):
    long_name = "x" * 20_000  # ten times the bound on the message: echoed in full, it could not pass
    for text in (GOOD.replace("strategy: basic", f"strategy: {long_name}"), GOOD + f"{long_name}: 1\n",
                 GOOD.replace("parser: json", f"parser: {{name: json, options: {{}}}}\ninstances: {{conditions: [{long_name}]}}")):
        message = refusal(write(tmp_path, text))
        assert len(message) < 2000, message[:300]


@pytest.mark.parametrize(
    "data",
    [b"\xff\xfe\x00d\x00a\x00t\x00a", "dataset: caf\xe9\n".encode("latin-1"), bytes(range(256)) * 4],
    ids=["utf-16", "latin-1", "binary"],
)
def test_a_file_that_is_not_utf8_text_is_a_clear_error(tmp_path, data):
    path = tmp_path / "pipeline.yaml"
    path.write_bytes(data)
    message = refusal(path)
    assert "UTF-8" in message or "text" in message


def test_control_characters_are_a_clear_error_naming_the_line(tmp_path):
    path = tmp_path / "pipeline.yaml"
    path.write_bytes(GOOD.encode() + b"x-bad: \x00\x01\n")
    message = refusal(path)
    assert "line 6" in message and "Traceback" not in message


# -- duplicate keys ------------------------------------------------------------------------------
def test_a_duplicate_key_is_an_error_naming_both_lines(tmp_path):
    message = refusal(write(tmp_path, GOOD + "strategy: cot\n"))
    assert "'strategy'" in message and "line 3" in message and "line 6" in message


def test_a_duplicate_nested_key_is_an_error(tmp_path):
    message = refusal(write(tmp_path, GOOD + "retry:\n  attempts: 2\n  attempts: 3\n"))
    assert "'attempts'" in message and "retry" in message and "line 8" in message


def test_a_duplicate_key_in_a_sweep_is_an_error(tmp_path):
    write(tmp_path, GOOD, "base.yaml")
    path = write(tmp_path, "base: base.yaml\noutput: runs/s\noutput: runs/t\n", "sweep.yaml")
    assert "'output'" in refusal(path, load_sweep)


def test_a_merge_key_is_not_a_duplicate(tmp_path):
    text = "base:\n" + textwrap.indent(GOOD + "retry: &r {attempts: 2, max_wait: 3}\n", "  ")
    text += "output: runs/s\noverrides:\n  patient:\n    retry:\n      <<: *r\n      attempts: 4\n"
    sweep, _, _ = load_sweep(write(tmp_path, text, "sweep.yaml"))
    assert sweep.overrides["patient"]["retry"] == {"attempts": 4, "max_wait": 3}


# -- numbers ------------------------------------------------------------------------------------
def test_runs_are_bounded(tmp_path):
    message = refusal(write(tmp_path, GOOD + "runs: 100000000\n"))
    assert "runs" in message and str(MAX_RUNS) in message and "line 6" in message


def test_a_long_list_of_runs_is_bounded(tmp_path):
    message = refusal(write(tmp_path, GOOD + f"runs: {list(range(MAX_RUNS + 1))}\n"))
    assert "runs" in message


@pytest.mark.parametrize(
    "text",
    ["retry: {initial_wait: .inf}", "retry: {max_wait: .inf}", "retry: {initial_wait: .nan}", "timeout: .inf",
     "retry: {initial_wait: 1.0e+300}", "retry: {attempts: 1000000000}"],
)
def test_waits_are_finite_and_bounded(tmp_path, text):
    message = refusal(write(tmp_path, GOOD + text + "\n"))
    assert "line 6" in message


def test_sensible_waits_load(tmp_path):
    config = load_pipeline(write(tmp_path, GOOD + "retry: {attempts: 8, initial_wait: 0.5, max_wait: 300}\ntimeout: 600\n"))
    assert config.retry.max_wait == 300 and config.timeout == 600


# -- output --------------------------------------------------------------------------------------
def test_output_naming_an_existing_file_is_a_clear_error(tmp_path):
    (tmp_path / "taken").write_text("not a folder")
    message = refusal(write(tmp_path, GOOD.replace("runs/x", str(tmp_path / "taken"))))
    assert "output" in message and "line 5" in message and "file" in message


def test_output_under_an_existing_file_is_a_clear_error(tmp_path):
    (tmp_path / "taken").write_text("not a folder")
    message = refusal(write(tmp_path, GOOD.replace("runs/x", str(tmp_path / "taken" / "run"))))
    assert "output" in message and "file" in message


def test_povagent_run_on_a_bad_config_prints_a_message_not_a_traceback(tmp_path):
    path = write(tmp_path, GOOD + "retry: {initial_wait: .inf}\nretry: {attempts: 2}\n")
    child = subprocess.run([sys.executable, "-m", "povagent.cli", "run", str(path), "--quiet"], capture_output=True, text=True, timeout=60)
    assert child.returncode != 0
    assert "Traceback" not in child.stderr and str(path) in child.stdout + child.stderr
