"""The ``tiny-model`` command: a tiny vision-language checkpoint to try the in-process
backend (and training) with no download.

It writes one of :mod:`povagent.testing.tiny_checkpoints`' folders (random weights, a tokenizer
trained on the spot, a processor with a chat template): ``backend: {name: transformers,
options: {model: FOLDER}}`` loads it like any Hugging Face checkpoint, on a CPU, in a second.
Its answers are nonsense; what it shows is the path from a folder to rows. It never writes into
a folder that holds anything, so it cannot overwrite a real checkpoint.
"""

from __future__ import annotations

from pathlib import Path

import typer

from povagent.cli import app

#: The architectures it builds, by name: (builder in povagent.testing.tiny_checkpoints, what to know).
ARCHITECTURES = {
    "idefics3": ("build_idefics3", "loads without remote code"),
    "qwen2-vl": ("build_qwen2_vl", "its processor is remote code: load it with trust_remote_code: true"),
}
#: What to install when transformers is missing.
LOCAL_EXTRA = "pip install torch, then pip install 'povagent[local]'"


def build_tiny_checkpoint(folder: Path, architecture: str = "idefics3", seed: int = 0) -> Path:
    """Write a tiny ``architecture`` checkpoint (one of :data:`ARCHITECTURES`) into ``folder``,
    which must not exist or be empty; the same seed writes the same weights."""
    from povagent.errors import ConfigError, PovagentError

    if architecture not in ARCHITECTURES:
        raise ConfigError(f"no tiny {architecture!r} checkpoint: choose one of {', '.join(ARCHITECTURES)}")
    folder = Path(folder)
    if folder.is_symlink() or (folder.exists() and (not folder.is_dir() or any(folder.iterdir()))):
        raise ConfigError(f"{folder}: exists and is not an empty folder; name a new folder for the checkpoint")
    try:
        from povagent.testing import tiny_checkpoints
    except ImportError:
        raise PovagentError(f"a tiny checkpoint needs torch and transformers: {LOCAL_EXTRA}") from None
    try:
        builder = getattr(tiny_checkpoints, ARCHITECTURES[architecture][0])
        return Path(builder(folder, seed=seed))
    except ImportError as exc:
        raise PovagentError(f"a tiny checkpoint needs torch and transformers ({exc.name or exc} is missing): {LOCAL_EXTRA}") from None


@app.command("tiny-model")
def tiny_checkpoint_command(
    folder: Path = typer.Argument(..., metavar="FOLDER", help="Where to write it: a new or empty folder."),
    architecture: str = typer.Option(
        "idefics3", "--architecture", metavar="NAME", help="idefics3 (loads without remote code) or qwen2-vl (needs trust_remote_code: true)."
    ),
    seed: int = typer.Option(0, "--seed", metavar="N", help="Seed of the random weights (the same seed writes the same weights)."),
) -> None:
    """Write a tiny checkpoint to try models with no download.

    A tiny vision-language checkpoint (random weights, nothing downloaded) for the transformers
    backend or a training script, on a CPU. Its answers are nonsense: it shows a folder becoming rows, not a model's skill. Needs torch
    and the local extra (pip install torch, then pip install 'povagent[local]').
    """
    made = build_tiny_checkpoint(folder, architecture, seed)
    note = ARCHITECTURES[architecture][1]
    typer.echo(f"{made}: a tiny {architecture} checkpoint ({note}); try it with backend: {{name: transformers, options: {{model: {made}}}}}")
