"""The embeddable grounding agent: a robot's frames and a user's sentence in, a goal out.

``from povagent.agent import GroundingAgent`` is the public entry point; the agent sends its
requests through the same engine as the runner (:mod:`povagent.engine`). One room per job:
``grounding_agent`` (the agent), ``frame_inputs`` (what a robot app hands it, checked),
``shown_frame`` (a frame letterboxed, named and encoded once, reusable across calls),
``prepared_call`` (the call's image store and the synthetic instance), ``ask_factory`` (how a
strategy asks the model), ``solver_cameras`` (the robot's cameras for a strategy that solves
the geometry), ``localization`` (the result, and how an answer becomes it).

Nothing here reads a dataset, writes result rows or scores: the agent embeds, it does not evaluate.
"""

from povagent.agent.ask_factory import AGENT_RETRY, AskFactory, default_ask_factory
from povagent.agent.frame_inputs import FrameInput, load_frame
from povagent.agent.grounding_agent import GroundingAgent
from povagent.agent.localization import Localization
from povagent.agent.shown_frame import ShownFrame
from povagent.agent.solver_cameras import PosedSolver
from povagent.geometry.goals import PinholeCamera, Plane

__all__ = [
    "AGENT_RETRY",
    "AskFactory",
    "FrameInput",
    "GroundingAgent",
    "Localization",
    "PinholeCamera",
    "Plane",
    "PosedSolver",
    "ShownFrame",
    "default_ask_factory",
    "load_frame",
]
