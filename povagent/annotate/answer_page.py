"""Answer mode's side of the page: the open question, its images, and the person's answer.

Images are found by question number and image index in the open question's own request (the
request the strategy built, the images the model would be sent), never by a name the page sends.
"""

from __future__ import annotations

import threading
from typing import Any

from povagent.annotate.desk import AnswerDesk, AnswerRefused


class AnswerPage:
    """The page's view of one annotator's desk (a :class:`~povagent.annotate.server.PageApp`)."""

    def __init__(self, desk: AnswerDesk, wait_s: float = 10.0) -> None:
        self.desk = desk
        self.wait_s = wait_s
        #: set once a reply has told the page the session is over: the server keeps serving
        #: until then (a few seconds at most), so an open page says "All done", not "gone"
        self.told_finished = threading.Event()

    def state(self) -> dict[str, Any]:
        """The question to show (waits up to ``wait_s`` for one), progress, and whether the
        session is over."""
        question = self.desk.current(self.wait_s)
        finished = question is None and self.desk.finished
        if finished:
            self.told_finished.set()
        return {
            "mode": "answer",
            "who": self.desk.annotator,
            "done": self.desk.done,
            "total": self.desk.total,
            "finished": finished,
            "question": question.page() if question is not None else None,
        }

    def image(self, number: int, index: int) -> tuple[bytes, str] | None:
        """Image ``index`` of the open question ``number``."""
        question = self.desk.question(number)
        if question is None:
            return None
        hashes = question.image_hashes()
        if index >= len(hashes):
            return None
        image = hashes[index]
        return question.images.encoded_bytes(image), question.images.info(image).media_type

    def post(self, action: str, body: dict[str, Any]) -> dict[str, Any]:
        """``answer``: the person's answer to the open question; replies once its row is saved."""
        if action != "answer":
            raise KeyError(action)
        number = body.get("question")
        if not isinstance(number, int) or isinstance(number, bool):
            raise AnswerRefused("question must be the number of the open question")
        return {"saved": self.desk.answer(number, body)}
