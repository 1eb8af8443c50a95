"""Options several commands share, declared once so their flags and help read the same everywhere."""

from __future__ import annotations

from typing import Any

import typer


def strict_option() -> Any:
    """``--strict``: stop at the first bad house or pair instead of reporting and skipping it."""
    return typer.Option(False, "--strict", help="Stop at the first bad house or pair of the dataset (default: report it, skip it, go on).")


def keep_errors_option() -> Any:
    """``--keep-errors/--retry-errors``: what a resumed run does with keys that failed before."""
    return typer.Option(
        False,
        "--keep-errors/--retry-errors",
        help="What to do with keys that failed in an earlier session (infra_error: no answer): keep their "
        "rows as they are, or try them again.",
    )


def trust_remote_code_option() -> Any:
    """``--trust-remote-code``: the one way a user lets a checkpoint's own Python code run."""
    return typer.Option(
        False,
        "--trust-remote-code",
        help="Let a checkpoint's own Python code run (the transformers backend; a YAML file cannot turn this on). "
        "Only for checkpoints whose code you have read and trust: it runs with your rights.",
    )
