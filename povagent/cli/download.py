"""Command ``download``: fetch the POVBench release from the Hugging Face Hub into its cache."""

from __future__ import annotations

from pathlib import Path

import typer

from povagent.cli import app


@app.command("download")
def download_command(
    repo_id: str = typer.Argument(
        "owl-owl/POVBench", metavar="REPO", help="Dataset repository on the Hugging Face Hub (default: the POVBench release)."
    ),
    conditions: list[str] | None = typer.Option(
        None, "--conditions", "-c", metavar="CONDITION",
        help="Fetch only what these conditions read (a/inferred, b/stated, c/given; repeat or comma-separate). "
        "Given alone skips the exploration frames. Default: the whole release.",
    ),
    revision: str | None = typer.Option(None, "--revision", metavar="REV", help="Branch, tag or commit (default: main)."),
    offline: bool = typer.Option(False, "--offline", help="Only read the cache, download nothing (as HF_HUB_OFFLINE=1 does)."),
    cache_dir: Path | None = typer.Option(
        None, "--cache-dir", metavar="FOLDER", help="Cache folder (default: the Hugging Face cache, HF_HOME / HF_HUB_CACHE)."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Do not show progress bars."),
) -> None:
    """Download the POVBench release and print its folder.

    The release goes into the Hugging Face cache. Use the printed folder as
    'dataset: {path: ...}' in a pipeline, or name the repository there
    ('dataset: {hub: owl-owl/POVBench}') and let run fetch it. Set HF_ENDPOINT for a mirror;
    with HF_HUB_OFFLINE=1 (or --offline) only the cache is read.
    """
    from povagent.dataset.hub import download_release, release_size

    release = download_release(
        repo_id,
        revision=revision,
        conditions=conditions or None,
        cache_dir=cache_dir,
        offline=True if offline else None,
        progress=not quiet,
    )
    files, size = release_size(release.root)
    typer.echo(f"{release.describe()}  ({files} files, {size / 2**20:.1f} MiB)")
    typer.echo(str(release.root))
