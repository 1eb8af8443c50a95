"""The embeddable grounding agent: a robot's frames and a user's sentence in, a goal out.

``from povagent.agent.grounding_agent import GroundingAgent`` is the public entry point; the agent sends its
requests through the same engine as the runner (:mod:`povagent.engine`).
"""

from povagent.agent.grounding_agent import GroundingAgent, Localization

__all__ = ["GroundingAgent", "Localization"]
