"""Hostile checkpoint folders end in one line naming the file, through ``povagent run``, before
``transformers`` (or torch) reads anything: a table of attacks, each a folder built here."""

from __future__ import annotations

import json
import os
import re
import struct
import time
from pathlib import Path
from typing import Callable

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import ConfigError, ReadTargetError
from povagent_plugins.backends.checkpoint_checks import check_checkpoint_folder

pytestmark = pytest.mark.timeout(30)


def safetensors_bytes(header: dict, data: bytes = b"") -> bytes:
    """A safetensors file: the header's length, the header, the data."""
    raw = json.dumps(header).encode()
    return struct.pack("<Q", len(raw)) + raw + data


def sound_checkpoint(folder: Path) -> Path:
    """A folder shaped like a checkpoint (config, one safetensors file), never loaded here."""
    folder.mkdir()
    (folder / "config.json").write_text(json.dumps({"model_type": "qwen2_vl"}))
    header = {"w": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]}}
    (folder / "model.safetensors").write_bytes(safetensors_bytes(header, b"\0" * 8))
    return folder


def _pickle_weights(folder: Path) -> None:
    (folder / "model.safetensors").unlink()
    (folder / "pytorch_model.bin").write_bytes(b"\x80\x04\x95 a pickle")


def _config_a_list(folder: Path) -> None:
    (folder / "config.json").write_text("[1, 2, 3]")


def _header_claiming_2_62_bytes(folder: Path) -> None:
    (folder / "model.safetensors").write_bytes(struct.pack("<Q", 1 << 62) + b"{}")


def _tensor_claiming_2_62_bytes(folder: Path) -> None:
    header = {"w": {"dtype": "F32", "shape": [1 << 60], "data_offsets": [0, 1 << 62]}}
    (folder / "model.safetensors").write_bytes(safetensors_bytes(header, b"\0" * 8))


def _index_linked_to_dev_zero(folder: Path) -> None:
    os.symlink("/dev/zero", folder / "model.safetensors.index.json")


def _index_a_fifo(folder: Path) -> None:
    os.mkfifo(folder / "model.safetensors.index.json")


def _tokenizer_a_fifo(folder: Path) -> None:
    os.mkfifo(folder / "tokenizer.json")


def _weight_map_leaving_the_folder(folder: Path) -> None:
    (folder / "model.safetensors.index.json").write_text(json.dumps({"weight_map": {"w": "../../etc/passwd"}}))


#: (attack, what the one line says)
ATTACKS: dict[str, tuple[Callable[[Path], None], str]] = {
    "pickle weights only": (_pickle_weights, r"pickle files \(pytorch_model\.bin\).*safetensors weights only"),
    "config.json a list": (_config_a_list, r"config\.json: holds a JSON list, not an object"),
    "safetensors header claiming 2^62 bytes": (_header_claiming_2_62_bytes, r"model\.safetensors: its safetensors header claims 4611686018427387904 bytes"),
    "tensor claiming 2^62 bytes": (_tensor_claiming_2_62_bytes, r"model\.safetensors: tensor 'w' claims data outside the file"),
    "index linked to /dev/zero": (_index_linked_to_dev_zero, r"index\.json: checkpoint file is a device, not a regular file"),
    "index a FIFO": (_index_a_fifo, r"index\.json: checkpoint file is a named pipe \(FIFO\)"),
    "tokenizer a FIFO": (_tokenizer_a_fifo, r"tokenizer\.json: checkpoint file is a named pipe \(FIFO\)"),
    "weight_map leaving the folder": (_weight_map_leaving_the_folder, r"weight_map names '\.\./\.\./etc/passwd', not a file inside the folder"),
}


@pytest.mark.parametrize("attack", list(ATTACKS))
def test_a_hostile_checkpoint_folder_is_one_line_through_run_before_anything_loads(attack, tmp_path, mini_root):
    folder = sound_checkpoint(tmp_path / "checkpoint")
    damage, says = ATTACKS[attack]
    damage(folder)
    pipeline = tmp_path / "run.yaml"
    pipeline.write_text(yaml.safe_dump({
        "dataset": str(mini_root),
        "backend": {"name": "transformers", "options": {"model": str(folder)}},
        "output": str(tmp_path / "out"),
    }))
    started = time.monotonic()
    result = CliRunner().invoke(app, ["run", str(pipeline)])
    assert time.monotonic() - started < 20
    exc = result.exception
    assert isinstance(exc, ConfigError | ReadTargetError), f"not a one-line error: {type(exc).__name__}: {exc}"
    message = str(exc)
    assert "\n" not in message and str(folder) in message
    assert re.search(says, message), message
    assert not (tmp_path / "out" / "results.jsonl").exists()


def test_a_sound_folder_passes_the_checks(tmp_path):
    check_checkpoint_folder(sound_checkpoint(tmp_path / "checkpoint"))


def test_pickle_weights_beside_safetensors_pass_because_only_safetensors_are_loaded(tmp_path):
    folder = sound_checkpoint(tmp_path / "checkpoint")
    (folder / "pytorch_model.bin").write_bytes(b"\x80\x04\x95 a pickle")
    check_checkpoint_folder(folder)


def test_a_loop_of_links_in_the_folder_is_one_line(tmp_path):
    folder = sound_checkpoint(tmp_path / "checkpoint")
    os.symlink(folder / "b.json", folder / "a.json")
    os.symlink(folder / "a.json", folder / "b.json")
    with pytest.raises(ConfigError, match=r"a\.json: cannot be read \(Too many levels of symbolic links\)"):
        check_checkpoint_folder(folder)
