"""Long system names beside the "Why it fails" bars wrap onto lines; none is squeezed or cut."""

from __future__ import annotations

import re

from povagent.report.plots import StackedBar, stacked_bars, wrapped_lines

LONG = "hosted_vllm/Qwen/Qwen3-VL-32B-Instruct-AWQ-with-a-long-suffix · spatial-cot-with-options"


def bars(group: str) -> list[StackedBar]:
    return [StackedBar(group, c, {"frame": 0.5, "correct": 0.5}, {}) for c in ("Inferred", "Stated")]


def test_a_long_system_name_wraps_onto_lines_and_is_never_squeezed():
    svg = stacked_bars("Why", bars(LONG) + bars("center"), ["frame", "correct"], ["#000", "#111"])
    label = next(t for t in re.findall(r"<text[^>]*>.*?</text>", svg) if "<tspan" in t and "Qwen" in t)
    lines = re.findall(r"<tspan[^>]*>(.*?)</tspan>", label)
    assert len(lines) >= 2 and "textLength" not in label
    assert "".join(lines).replace(" ", "") == LONG.replace(" ", "")  # every character kept
    assert f"<title>{LONG}</title>" in label  # the whole name on hover too


def test_wrapped_lines_break_after_separators_and_keep_every_character():
    lines = wrapped_lines("qwen3-vl-8b-transformers · spatial-cot", 16)
    assert all(len(line) <= 16 for line in lines)
    assert "".join(lines).replace(" ", "") == "qwen3-vl-8b-transformers·spatial-cot"


def test_the_next_group_starts_below_a_wrapped_name():
    svg = stacked_bars("Why", bars(LONG * 2) + bars("center"), ["frame"], ["#000"])
    last_line_y = max(float(y) for y in re.findall(r'<text x="8" y="([\d.]+)"', svg))
    center_y = float(re.search(r'<text x="8" y="([\d.]+)"[^>]*><tspan[^>]*>center<', svg).group(1))
    long_label = next(t for t in re.findall(r"<text[^>]*>.*?</text>", svg) if "Qwen" in t)
    n = long_label.count("<tspan")
    first_y = float(re.search(r'y="([\d.]+)"', long_label).group(1))
    assert center_y > first_y + (n - 1) * 14
    assert last_line_y == center_y
