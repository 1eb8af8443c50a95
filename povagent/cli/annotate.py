"""``povagent annotate``: serve the local page where a person answers as a system."""

from __future__ import annotations

import asyncio
import threading
from pathlib import Path

import typer

from povagent.cli import app


@app.command("annotate")
def annotate_command(
    config: Path = typer.Argument(
        ..., metavar="CONFIG",
        help="A pipeline YAML with `backend: human` and `annotator: NAME` (docs/how-to/human-study.md).",
    ),
    port: int = typer.Option(0, "--port", min=0, max=65535, metavar="PORT", help="The port on 127.0.0.1 to serve on (0: a free one, printed)."),
) -> None:
    """Serve a local page where a person answers or judges.

    The page is on 127.0.0.1 only, with a random token in its address.

    Answer mode (annotator: NAME): the person sees what a model is shown and answers by clicking a
    point or choosing an option; each answer is a row of an ordinary run folder (the config's
    output:), so report, rescore and compare show the person as the system human:NAME. Judge mode
    (judge: NAME, runs: [...]): the runs' predictions, drawn on their frames, blind and shuffled,
    judged success / failure / can't tell. Stop at any time (Ctrl-C, closing the tab): the same
    command resumes at the next item.
    """
    from povagent.annotate.study_config import JudgeStudy, load_study

    study = load_study(config)
    if isinstance(study, JudgeStudy):
        _judge(study, port)
        return
    from povagent.annotate.answer_page import AnswerPage
    from povagent.annotate.answer_session import AnswerSession
    from povagent.annotate.desk import AnswerDesk, serving
    from povagent.annotate.server import AnnotateServer
    from povagent.run.components import create_components
    from povagent.run.stop_signals import sigterm_as_interrupt

    desk = AnswerDesk(study.annotator)
    # the session (its plugins, each component's options) and the port first: whatever is
    # refused is refused before the page's address and token are printed
    session = AnswerSession(study.pipeline, desk, seed=study.seed, pairs_apart=study.pairs_apart)
    create_components(study.pipeline, session.host)
    page = AnswerPage(desk)
    server = AnnotateServer(page, port)
    server.start()
    typer.echo(f"annotating as human:{study.annotator} into {study.pipeline.output}")
    typer.echo(f"open {server.url}", err=False)
    told: threading.Event | None = None
    try:
        with serving(desk), sigterm_as_interrupt() as stop:
            result = asyncio.run(session.run())
        told = page.told_finished  # a finished session waits (briefly) for the page to hear it
    except KeyboardInterrupt:
        typer.echo(f"{stop.what}: every saved answer is kept in {study.pipeline.output}; run `povagent annotate {config}` again to resume", err=True)
        raise typer.Exit(stop.exit_code) from None
    finally:
        desk.finish()
        server.close(told=told)
    typer.echo(f"done: {result.summary.rows.answered if result.summary.rows else 0} answers in {result.run_dir}")
    raise typer.Exit(result.exit_code)


def _judge(study, port: int) -> None:
    """Serve judge mode until every prediction is judged or the command is stopped."""
    import time

    from povagent.annotate.judge_page import JudgePage, judge_items
    from povagent.annotate.server import AnnotateServer
    from povagent.results.judgements import JudgementJournal

    journal = JudgementJournal(study.judgements, study.judge, study.judgements_below)
    page = JudgePage(judge_items(study.runs), journal, study.judge, study.seed)
    server = AnnotateServer(page, port)
    server.start()
    typer.echo(f"judging as {study.judge} into {page.journal.path}")
    typer.echo(f"open {server.url}")
    try:
        while not page.state_finished():
            time.sleep(0.5)
    except KeyboardInterrupt:
        typer.echo(f"interrupted: every saved judgement is kept in {page.journal.path}; run the same command again to resume", err=True)
        raise typer.Exit(130) from None
    finally:
        server.close()
    typer.echo(f"done: {page.total} predictions judged, in {page.journal.path}")
