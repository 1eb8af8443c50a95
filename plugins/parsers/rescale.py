"""The ``rescale-1000`` parser: the ``json`` reading, with answers on the wrong scale repaired.

Some models answer on the 0-1000 convention they were trained on (Qwen3-VL-32B: 21% of its
Inferred answers fell out of frame) or in fractions of the image, although pixels on
``[0, W-1] x [0, H-1]`` were asked. This parser reads the answer as ``json`` does, then applies
the decision rule below to the chosen ``(x, y)`` (the frame index is never touched). A repaired
row has status ``repaired``, ``repair`` says which convention was assumed, and ``reason`` why.

Decision rule, first match wins:

1. **Fractions.** ``0 <= x <= 1`` and ``0 <= y <= 1`` and at least one is not a whole number
   -> ``x*W, y*H``. (An honest pixel answer inside the top-left pixel with decimals is the
   only pixel answer this catches: not a plausible answer.)
2. **0-1000, out of range.** The answer overshoots the frame by more than a margin
   (``x > W-1+m`` or ``y > H-1+m``, ``m = max(2, 0.02*W)`` resp. ``H``: about 10 px at 512),
   and both ``x`` and ``y`` lie in ``[0, 1000]`` -> ``x/1000*W, y/1000*H``.
3. **0-1000, declared.** The text says it uses a 0-1000 scale (``0-1000``, ``0 to 1000``,
   ``[0, 1000]``, ``normalized to 1000``, ``per mille``, ``thousandths``), not negated just
   before (``not``, ``n't``, ``no``, ``instead of``, ``rather than``, ``unlike`` in the 30
   characters before it), and both values lie in ``[0, 1000]`` -> rescaled as in 2, even when
   in range. A fraction such as ``300/1000`` is *not* a declaration: reasoning writes such
   ratios about the scene, and reading one as a scale would change an honest pixel answer.
4. Otherwise the answer is left exactly as ``json`` reads it: an honest in-range pixel answer
   is never changed, and an answer out of range that fits no rule stays ``out_of_range``.

Known ambiguous cases (documented, tested):

* a 0-1000 answer whose two values are both ``<= W-1`` (e.g. ``(300, 400)``) is
  indistinguishable from pixels and is *not* repaired unless the text declares the scale;
* an overshoot within the margin (``x = 512`` or ``518`` at W = 512) is read as a pixel answer
  off by a little, not as 0-1000 (it stays ``out_of_range``; the scorer clamps it);
* a pixel answer for a bigger assumed image (e.g. 0-1023) with values ``<= 1000`` is rescaled
  as 0-1000 (within 2.4% of the right answer); values above 1000 are left out of range;
* negative values are never repaired;
* the object judged is the one the official reading chooses (last in range, else last) before
  any rescaling: in an answer with an intermediate 0-1000 object that happens to be in pixel
  range and a final one past it, the intermediate one is taken, as the official parser does;
* a declaration anywhere in the text counts, also one about a different number in the
  reasoning ("the lamp is at 0-1000 coordinates (200, 300)") when the final answer is an
  in-range pixel answer: rare, and a model that says it thinks in 0-1000 usually answers so.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus
from povagent.answers.validation import judge, relative_to_pixels
from povagent.interfaces import Parser
from povagent_plugins.parsers.json_answer import choose

#: Text declaring the 0-1000 convention.
DECLARED_1000 = re.compile(
    r"\b0\s*(?:-|–|~|to)\s*1000\b|\[\s*0\s*,\s*1000\s*\]"
    r"|normali[sz]ed\s+(?:to|on|in)\s+(?:a\s+|the\s+)?(?:\[?0\s*,\s*)?1000\b|per[\s-]?mille|thousandths",
    re.IGNORECASE,
)
#: A negation just before a declaration ("pixels, not 0-1000"): then it declares nothing.
_NEGATION = re.compile(r"\b(?:not|no|never|instead\s+of|rather\s+than|unlike)\b|n't\b", re.IGNORECASE)
_NEGATION_WINDOW = 30


def declares_1000(text: str) -> bool:
    """True when ``text`` says it uses the 0-1000 convention (and does not negate it)."""
    for m in DECLARED_1000.finditer(text):
        if not _NEGATION.search(text[max(0, m.start() - _NEGATION_WINDOW) : m.start()]):
            return True
    return False


FRACTIONS = "rescaled 0-1 fractions -> pixels"
THOUSANDTHS = "rescaled 0-1000 -> pixels"


def overshoot_margin(size: int) -> float:
    """How far past the last pixel an answer may go and still be read as pixels."""
    return max(2.0, 0.02 * size)


def convention(x: float, y: float, spec: AnswerSpec, text: str) -> tuple[str | None, str]:
    """Which convention an answer seems to use: ``(repair, why)``; repair ``None`` for pixels."""
    w, h = spec.width, spec.height
    if 0 <= x <= 1 and 0 <= y <= 1 and not (float(x).is_integer() and float(y).is_integer()):
        return FRACTIONS, f"x={x:g}, y={y:g} are fractions of the image"
    in_1000 = 0 <= x <= 1000 and 0 <= y <= 1000
    if in_1000 and (x > w - 1 + overshoot_margin(w) or y > h - 1 + overshoot_margin(h)):
        return THOUSANDTHS, f"x={x:g}, y={y:g} overshoot [0, {w - 1}] x [0, {h - 1}] but fit 0-1000"
    if in_1000 and declares_1000(text):
        return THOUSANDTHS, "the answer declares a 0-1000 scale"
    return None, ""


class Rescale1000Parser(Parser):
    """``json`` plus the repair of 0-1000 and 0-1 answers (see the module docstring)."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = '`json`, then a documented rule for answers on 0-1000 or in 0-1 fractions'
    beside_official = 'adds: rescaling to pixels (status `repaired`)'

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Parse ``text``, repairing the scale when the rule says so; never raises."""
        text = text or ""
        cand, parsed = choose(text, spec)
        if cand is None or parsed.status is ParseStatus.UNPARSEABLE:
            return parsed
        repair, why = convention(cand.x, cand.y, spec, text)
        if repair is None:
            return parsed
        scale = 1.0 if repair == FRACTIONS else 1000.0
        x = relative_to_pixels(cand.x, scale, spec.width)
        y = relative_to_pixels(cand.y, scale, spec.height)
        if parsed.repair:  # the frame was already read from the text: keep saying so
            repair = f"{parsed.repair}; {repair}"
        return judge(spec, x, y, parsed.selected_image, span=parsed.span, repair=repair, note=why)


@hookimpl
def register_parsers(register) -> None:
    """Contribute the rescale-1000 parser."""
    register(
        "rescale-1000",
        Rescale1000Parser,
        description="json, plus repair of answers given on 0-1000 or as 0-1 fractions (documented rule)",
    )
