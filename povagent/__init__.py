"""povagent: contextual observer grounding.

Evaluate vision-language models on POVBench and embed a grounding agent in robot apps.
The core here is pure (data model, geometry, metric, pipeline contracts); files, network and
clocks live in the runner, the backends and the CLI.
"""

__version__ = "0.1.0"

from povagent.hookspecs import hookimpl  # the one decorator plugins need

__all__ = ["__version__", "hookimpl"]
