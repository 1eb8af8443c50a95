"""A run of the ``queued`` backend made once a module, outside any one test's fixtures."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def run_with_queued_replies(pipeline: Path, replies: list[str]) -> Any:
    """Run ``pipeline`` (its backend ``queued``) answering ``replies`` in order, on a plugin host
    of its own (as the ``queued_backend`` fixture makes one): a run a module makes once, outside
    any one test's fixtures; the host is the test's again once the run is done."""
    from povagent import hookimpl, plugins
    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline
    from povagent.testing.pytest_plugin import QueuedBackendHandle

    handle = QueuedBackendHandle()

    class Queued:
        @hookimpl
        def register_backends(self, register) -> None:
            register("queued", handle.factory, description="canned replies (tests)")

    host = plugins.build_plugin_host(strict=False)
    host.add_plugin(Queued(), name="povagent-testing-queued-backend")
    previous, plugins._OVERRIDE = plugins._OVERRIDE, host
    try:
        handle.queue(*replies)
        return run_pipeline(load_pipeline(pipeline))
    finally:
        plugins._OVERRIDE = previous
