"""Requests as OpenAI chat messages (plugins/backends/openai_messages.py)."""

from __future__ import annotations

from PIL import Image

from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.exchange.messages import ImagePart, Message, Request, TextPart
from povagent_plugins.backends.openai_messages import openai_messages


def _request(*messages: Message) -> Request:
    return Request(messages=messages, answer=AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False))


def test_parts_keep_their_order_text_and_images_interleaved(store):
    a = store.add_pil(Image.new("RGB", (2, 2), "red")).image_hash
    b = store.add_pil(Image.new("RGB", (2, 2), "blue")).image_hash
    msg = Message("user", (TextPart("Image 0:"), ImagePart(a), TextPart("Image 1:"), ImagePart(b), TextPart("Q")))
    (out,) = openai_messages(_request(msg), store)
    assert out == {
        "role": "user",
        "content": [
            {"type": "text", "text": "Image 0:"},
            {"type": "image_url", "image_url": {"url": store.data_url(a)}},
            {"type": "text", "text": "Image 1:"},
            {"type": "image_url", "image_url": {"url": store.data_url(b)}},
            {"type": "text", "text": "Q"},
        ],
    }


def test_images_are_sent_as_png_data_urls(store):
    h = store.add_pil(Image.new("RGB", (2, 2))).image_hash
    (out,) = openai_messages(_request(Message("user", (ImagePart(h),))), store)
    assert out["content"][0]["image_url"]["url"].startswith("data:image/png;base64,")


def test_image_label_attribute_adds_no_text(store):
    # the strategy lays labels out as text parts; ImagePart.label must not be sent twice
    h = store.add_pil(Image.new("RGB", (2, 2))).image_hash
    (out,) = openai_messages(_request(Message("user", (ImagePart(h, label="Image 0:"),))), store)
    assert [p["type"] for p in out["content"]] == ["image_url"]


def test_system_and_assistant_text_are_plain_strings(store):
    out = openai_messages(
        _request(Message.text("system", "sys"), Message.text("user", "hi"), Message.text("assistant", "ok")), store
    )
    assert out[0] == {"role": "system", "content": "sys"}
    assert out[1] == {"role": "user", "content": [{"type": "text", "text": "hi"}]}
    assert out[2] == {"role": "assistant", "content": "ok"}
