"""The ``cot`` parser: the final-line JSON after free reasoning.

The CoT prompts ask for "ONLY the final JSON on the last line". This parser reads the object that
ends on the last line (trailing blank and code-fence lines skipped; an object pretty-printed over
several lines counts if it ends there) and takes it as the answer even when it is out of range:
it is the model's conclusion. When the last line holds no usable object it falls back to the
``json`` parser over the whole text (the reason says so). Never raises.
"""

from __future__ import annotations

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.answers.text import final_line_start, find_objects
from povagent.interfaces import Parser
from povagent_plugins.parsers.json_answer import candidates, choose, judge_candidate


class CotParser(Parser):
    """Final-line JSON, falling back to the official JSON reading of the whole text."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "`json` over the object on the last line (the CoT prompts' format), else `json` over the whole text"
    beside_official = 'adds: the final-line answer wins even when out of range'

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """Parse ``text`` (see the module docstring); never raises."""
        text = text or ""
        if not text.strip():
            return choose(text, spec)[1]
        objects = find_objects(text)
        tail = final_line_start(text)
        found, frame_from_text = candidates(text, spec, objects)
        final = [c for c in found if c.source.end > tail]
        if final:
            return judge_candidate(final[-1], spec, text, frame_from_text)
        parsed = choose(text, spec, objects)[1]
        note = "no JSON answer on the last line; read the whole text"
        return parsed.model_copy(update={"reason": f"{note}; {parsed.reason}" if parsed.reason else note})


@hookimpl
def register_parsers(register) -> None:
    """Contribute the cot parser."""
    register("cot", CotParser, description="JSON on the final line after reasoning; falls back to json over the whole text")
