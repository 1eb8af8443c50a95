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
    deadline: float = typer.Option(
        3600.0, "--deadline", metavar="SECONDS", min=0.001, help="Give up (cleanly, keeping only checked files) after this long."
    ),
    max_file_mib: float = typer.Option(
        64.0, "--max-file-mib", metavar="MIB", min=0.000001, help="Refuse a file the tree listing says is larger."
    ),
    max_total_mib: float = typer.Option(
        4096.0, "--max-total-mib", metavar="MIB", min=0.000001, help="Refuse a download whose files total more."
    ),
) -> None:
    """Download the POVBench release and print its folder.

    The release goes into the Hugging Face cache. Use the printed folder as
    'dataset: {path: ...}' in a pipeline, or name the repository there
    ('dataset: {hub: owl-owl/POVBench}') and let run fetch it. Set HF_ENDPOINT for a mirror;
    with HF_HUB_OFFLINE=1 (or --offline) only the cache is read. Nothing the server sends is
    trusted: a bad commit id, ETag or file name, bytes that differ from the tree listing, a cap
    or the deadline passed is a one-line error, and nothing is written outside the cache.
    """
    from pydantic import ValidationError

    from povagent.dataset.hub import download_release, release_size
    from povagent.dataset.hub_limits import DownloadLimits

    try:
        limits = DownloadLimits(deadline_s=deadline, max_file_mib=max_file_mib, max_total_mib=max_total_mib)
    except ValidationError as exc:
        raise typer.BadParameter(exc.errors()[0]["msg"]) from None

    release = download_release(
        repo_id,
        revision=revision,
        conditions=conditions or None,
        cache_dir=cache_dir,
        offline=True if offline else None,
        progress=not quiet,
        limits=limits,
    )
    files, size = release_size(release.root)
    typer.echo(f"{release.describe()}  ({files} files, {size / 2**20:.1f} MiB)")
    typer.echo(str(release.root))
