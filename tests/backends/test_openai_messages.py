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


def test_an_assistant_tool_call_and_its_result_are_sent_in_the_function_calling_form(store):
    from povagent.exchange.messages import ToolCall

    call = Message("assistant", (), (ToolCall("call_1", "turn", '{"degrees": 30}'),))
    result = Message("tool", (TextPart("View 1: turned 30 degrees"),), tool_call_id="call_1")
    sent_call, sent_result = openai_messages(_request(call, result), store)
    assert sent_call == {"role": "assistant", "content": None, "tool_calls": [
        {"id": "call_1", "type": "function", "function": {"name": "turn", "arguments": '{"degrees": 30}'}}]}  # fmt: skip
    assert sent_result == {"role": "tool", "content": "View 1: turned 30 degrees", "tool_call_id": "call_1"}


def test_a_plain_message_fingerprint_is_unchanged_by_the_tool_fields():
    request = _request(Message.text("user", "hi"))
    assert request.fingerprint() == {"messages": [{"role": "user", "parts": [{"text": "hi"}]}], "generation": {"max_tokens": 256}}


def test_tool_calls_read_from_an_answer_are_bounded_and_never_raise():
    from types import SimpleNamespace as NS

    from povagent.engine.received import MAX_ARGUMENTS_CHARS, MAX_TOOL_CALLS
    from povagent_plugins.backends.openai_messages import tool_calls_of

    many = [NS(id=f"c{k}", function=NS(name="turn", arguments="x" * (MAX_ARGUMENTS_CHARS + 10))) for k in range(MAX_TOOL_CALLS + 5)]
    calls = tool_calls_of(NS(choices=[NS(message=NS(tool_calls=many + [NS()]))]))
    assert len(calls) == MAX_TOOL_CALLS and all(len(c.arguments) == MAX_ARGUMENTS_CHARS for c in calls)
    odd = tool_calls_of(NS(choices=[NS(message=NS(tool_calls=[NS(id=None, function=NS(name=None, arguments={"a": 1}))]))]))
    assert (odd[0].id, odd[0].name, odd[0].arguments) == ("call_0", "", '{"a": 1}')
    assert tool_calls_of(NS(choices=[])) == ()
