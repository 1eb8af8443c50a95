"""Command ``schema``: print the JSON Schema of a file povagent writes (thin over
:mod:`povagent.run.output_schemas`)."""

from __future__ import annotations

import typer

from povagent.cli import app

#: The names ``povagent schema`` takes, in the order its help lists them.
SCHEMA_NAMES = ("summary", "row", "sweep", "export", "rescore-log")


@app.command("schema")
def schema_command(
    name: str = typer.Argument(
        ..., metavar="NAME",
        help="summary (a run's summary.json), row (a results.jsonl line), sweep (sweep.json), export (export.json) or rescore-log (rescore-log --json).",
    ),
) -> None:
    """Print the JSON Schema of a file povagent writes.

    The same schemas ship in the package (povagent/schemas/output_NAME.schema.json).
    """
    from povagent.errors import ConfigError
    from povagent.run.output_schemas import output_schema_text

    if name not in SCHEMA_NAMES:
        raise ConfigError(f"povagent schema {name!r}: one of {', '.join(SCHEMA_NAMES)}")
    typer.echo(output_schema_text(name), nl=False)
