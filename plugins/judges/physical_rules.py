"""The ``physical-rules`` surface judge: the generator's default, deterministic and offline.

The rules themselves live beside the generator (:class:`povagent.generate.judge.PhysicalRulesJudge`,
which reads the house geometry); this module only registers them under a name, as a third-party
judge plugin would. The generator (numpy, trimesh) is imported when a judge is made, not when
the plugin loads: every povagent command loads this module.
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl


def physical_rules_judge(**options: Any) -> Any:
    """Support, free-space and clearance rules on the house geometry (no options)."""
    from povagent.generate.judge import PhysicalRulesJudge

    return PhysicalRulesJudge(**options)


@hookimpl
def register_judges(register):
    """Register ``physical-rules``."""
    register(
        "physical-rules",
        physical_rules_judge,
        description="deterministic support, free-space and clearance rules on the house geometry (the default)",
    )
