"""A sweep's dry run: what each cell still has to do (keys, requests per turn, a rough token
estimate), finished keys subtracted, without calling any model.

``povagent sweep --dry-run`` prints it; the estimate counts a prompt's text and its images'
pixels (:data:`TOKENS_PER_IMAGE_PIXEL`), so it is a guide, not a bill.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from povagent.dataset.set_interface import EvaluationSet
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, TextPart
from povagent.interfaces import declares_turns, whole_answer_placeholders
from povagent.plugins import PluginHost, get_plugin_host
from povagent.run.pending import ensure_dataset, pending_keys
from povagent.run.sweep_grid import Cell

#: Rough prompt tokens per 512x512 image (ViT patches of 28 px); dry-run estimates only.
TOKENS_PER_IMAGE_PIXEL = 1.0 / (28 * 28)


@dataclass
class TurnCount:
    """What one turn of a cell's strategy still has to do (see :meth:`Strategy.plan_turns`)."""

    turn: int
    requests: int
    prompt_tokens: int
    max_completion_tokens: int
    note: str = ""


@dataclass
class DryRunCell:
    """What a cell still has to do: totals over the turns, and each sent turn's counts."""

    name: str
    n_total: int
    n_done: int
    requests: int
    prompt_tokens: int
    max_completion_tokens: int
    turns: list[TurnCount] = field(default_factory=list)
    #: False when the strategy overrides ``solve`` without ``plan_turns``: later turns unknown.
    turns_declared: bool = True


def dry_run(cells: list[Cell], *, host: PluginHost | None = None) -> list[DryRunCell]:
    """Requests still to make per cell and per turn (finished keys subtracted) and a rough
    token estimate, from the turns the strategy plans (:meth:`Strategy.plan_turns`).

    Tokens are estimated from one instance per condition: text at ~4 characters a token,
    images at ~1 token per 28x28 pixels, a placeholder for an earlier whole answer at that
    turn's ``max_tokens``; completions at each turn's ``max_tokens`` (an upper bound). A turn
    the strategy takes only sometimes is counted for every key (an upper bound too); a turn it
    works out itself is not a request.
    """
    datasets: dict[Any, EvaluationSet] = {}
    images = ImageStore()
    out: list[DryRunCell] = []
    for cell in cells:
        h = host or get_plugin_host(cell.config.plugins)
        ds = ensure_dataset(cell.config, datasets)
        total, done, pending = pending_keys(cell.config, ds)
        strategy = h.strategy(cell.config.strategy.name, cell.config.strategy.options)
        by_condition: dict[str, list[Any]] = {}
        for inst, _ in pending:
            by_condition.setdefault(str(inst.condition), []).append(inst)
        counts: dict[int, TurnCount] = {}
        for group in by_condition.values():
            planned = strategy.plan_turns(group[0], images)
            budgets = [t.request.generation.max_tokens or 0 for t in planned]
            for number, turn in enumerate(planned, start=1):
                if not turn.sent:
                    continue
                count = counts.setdefault(number, TurnCount(number, 0, 0, 0, turn.note))
                count.requests += len(group)
                count.prompt_tokens += math.ceil(_prompt_tokens(turn.request, images, budgets) * len(group))
                # no limit (None): the estimate counts none, so it is a lower bound for that turn
                count.max_completion_tokens += (turn.request.generation.max_tokens or 0) * len(group)
        turns = [counts[n] for n in sorted(counts)]
        out.append(
            DryRunCell(
                cell.name, total, done, sum(t.requests for t in turns), sum(t.prompt_tokens for t in turns),
                sum(t.max_completion_tokens for t in turns), turns, declares_turns(strategy),
            )
        )
    return out


def _prompt_tokens(request: Request, images: ImageStore, budgets: list[int]) -> float:
    """Rough prompt tokens of a planned request; a whole-answer placeholder counts as the
    budget (``max_tokens``) of the turn it stands for."""
    text = 0.0
    for m in request.messages:
        for p in m.parts:
            if isinstance(p, TextPart):
                text += len(p.text) / 4
                for turn in whole_answer_placeholders(p.text):
                    text += budgets[turn - 1] if turn <= len(budgets) else 0
    pixels = sum(images.info(h).width * images.info(h).height for h in request.image_hashes())
    return text + pixels * TOKENS_PER_IMAGE_PIXEL
