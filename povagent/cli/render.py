"""The ``render`` command: any camera of a generated house, as the active mode renders it."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from povagent.cli import app


def _position(text: str) -> tuple[float, float, float]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise typer.BadParameter(f"{text[:60]!r}: give three finite numbers X,Y,Z (metres)", param_hint="--cam-pos")
    return values[0], values[1], values[2]


@app.command("render")
def render_command(
    dataset: Path = typer.Argument(..., metavar="DATASET", help="A dataset made by `povagent generate` (this version)."),
    house: str = typer.Option(..., "--house", metavar="H", help="The house folder name, e.g. train_house_00000."),
    cam_pos: str = typer.Option(..., "--cam-pos", metavar="X,Y,Z", help="Camera position in metres (y up)."),
    yaw: float = typer.Option(..., "--yaw", metavar="Y", help="Yaw in degrees, as the dataset's cam_yaw (clockwise from above)."),
    horizon: float = typer.Option(..., "--horizon", metavar="H", help="Horizon in degrees, positive looks down."),
    fov: float = typer.Option(100.0, "--fov", min=1.0, max=179.0, metavar="DEGREES", help="Field of view in degrees (1-179)."),
    out: Path = typer.Option(..., "--out", metavar="FILE.png", help="Where to write the PNG."),
) -> None:
    """Render one camera of a generated house to a PNG (512x512).

    The camera of an exploration frame or an observer view gives that image byte for byte.
    A dataset this generator version did not make (the public release) is refused.
    """
    from povagent.active.house import render_view
    from povagent.geometry.camera import Camera

    position = _position(cam_pos)
    if not (math.isfinite(yaw) and math.isfinite(horizon)):
        raise typer.BadParameter("yaw and horizon must be finite numbers")
    _check_out(out)  # before the house is rebuilt: a bad --out costs no render
    data = render_view(dataset, house, Camera(position, yaw, horizon, fov, 512, 512))
    _write_png(out, data)
    typer.echo(f"{out} ({len(data)} bytes)")


def _check_out(out: Path) -> None:
    """``--out`` names a file: not empty, not a folder (one line otherwise)."""
    from povagent.errors import OutputFileError

    if not out.name or out.name in (".", ".."):
        raise OutputFileError(f"--out {str(out)!r}: name a file to write the PNG to (e.g. view.png)")
    if out.is_dir():
        raise OutputFileError(f"--out {out}: is a folder; name a file to write the PNG to (e.g. {out / 'view.png'})")


def _write_png(out: Path, data: bytes) -> None:
    """Write ``out`` whole (aside and renamed, never through a link planted there); a place that
    refuses the write is one line naming it."""
    from povagent.errors import OutputFileError, WriteTargetError, is_file_system_error
    from povagent.files.confined_write import write_inside

    try:
        out.parent.mkdir(parents=True, exist_ok=True)  # the folder the user named: theirs to place
        write_inside(out.parent, out.name, data)
    except WriteTargetError as exc:
        raise OutputFileError(f"--out {out}: {exc}") from None
    except OSError as exc:
        if not is_file_system_error(exc):
            raise
        raise OutputFileError(f"--out {out}: cannot write ({exc.strerror or exc}); choose a file in a folder you can write to") from None
