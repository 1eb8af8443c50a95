"""The ``povagent`` command line: a thin typer app; every command calls a library function.

Commands live in submodules by area (one job each) and attach themselves to :data:`app`;
importing them here keeps ``povagent --help`` complete while heavy libraries (litellm, trimesh)
are imported only inside the commands that need them.
"""

from __future__ import annotations

import importlib
import sys

import typer

app = typer.Typer(
    name="povagent",
    help="Contextual observer grounding: evaluate VLMs on POVBench, generate datasets, report.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # click's plain help: typer's rich panels print a type column beside every option, flags
    # included (`--strict <bool>`, even `--help <bool>`), and keep a docstring's line breaks
    rich_markup_mode=None,
)

#: Submodules that add commands to ``app`` (each owns its commands).
COMMAND_MODULES = (
    "povagent.cli.dataset_commands",    # validate, score
    "povagent.cli.pipeline_commands",   # run, sweep, plugins
    "povagent.cli.prompting",  # show-prompt, parse, rescore
    "povagent.cli.rescore_log_command",  # rescore-log
    "povagent.cli.generate",   # generate
    "povagent.cli.render",     # render
    "povagent.cli.reporting",  # report, export, compare
    "povagent.cli.quickstart_command", # quickstart
    "povagent.cli.download",   # download
    "povagent.cli.train",      # export-train
    "povagent.cli.tiny_checkpoint",  # tiny-model
    "povagent.cli.schema_command",     # schema
    "povagent.cli.ros",        # ros-node, ros-replay
    "povagent.cli.annotate",   # annotate
)

for _name in COMMAND_MODULES:
    try:
        importlib.import_module(_name)
    except ModuleNotFoundError as _exc:  # a command module not written yet
        if _exc.name != _name:
            raise


def main() -> None:
    """Console-script entry point: user-facing errors print a message, not a traceback.

    After ``run`` and ``sweep`` the process ends without the interpreter's teardown (seconds
    after litellm): see :mod:`povagent.cli.process_exit`.
    """
    from povagent.cli.process_exit import exit_now, fast_exit_allowed
    from povagent.engine.llm_import import freeze_after_loading
    from povagent.errors import NO_ROOM_ERRNOS, PovagentError, ResultsError

    freeze_after_loading()  # this process is povagent's own: litellm's objects may be frozen

    try:
        app()
    except PovagentError as exc:
        typer.echo(f"error: {exc}", err=True)
        sys.exit(2)
    except OSError as exc:
        if exc.errno not in NO_ROOM_ERRNOS:
            raise
        # a full disk is the user's to fix, wherever the write was (a config copy, a report page)
        typer.echo(f"error: {ResultsError.cannot_write(exc.filename or 'a file', exc)}", err=True)
        sys.exit(2)
    except SystemExit as done:
        if fast_exit_allowed():
            exit_now(done.code)
        raise
