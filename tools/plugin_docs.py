"""Generates the reference parts of ``docs/reference/plugins.md`` from the code, so the page cannot drift.

The page is hand-written prose with marked blocks that this module fills in::

    <!-- generated: hooks -->                       every hookspec of povagent/hookspecs.py
    <!-- generated: interfaces -->                  the base classes of povagent/interfaces.py
    <!-- generated: fields povagent.x.y:Class -->    a field table of a dataclass or pydantic model
    <!-- generated: include ../examples/a.py -->    a file's code (path from the page's folder)
    <!-- generated: parsers -->                     the built-in parsers: what each reads, beside ``official``
    <!-- generated: tools -->                       the built-in active-mode tools: arguments, what each does
    ...whatever is here is replaced...
    <!-- end generated -->

Run ``python tools/plugin_docs.py`` (from the repository root) after changing a hookspec, a
base class, one of those models or an included example; ``--check`` only says whether the page
is up to date (the test suite runs it). A field table's meanings are written here
(:data:`FIELD_NOTES`): a model that gains a field without a note, or loses one that has a note,
is an error, so the tables stay complete.

A tool of the repository, not of the installed package: it lives outside ``povagent/`` so the
runtime carries no docs generator. Reads modules and Markdown files (``docs/reference/plugins.md``, ``docs/explanation/official.md`` for its parser
table, ``docs/how-to/active.md`` for its tools table); imports only the built-in plugins, for those tables.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import inspect
import re
import sys
from pathlib import Path
from typing import Any, Callable

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

from povagent import hookspecs, interfaces

#: The page, from the repository root.
DEFAULT_PAGE = Path("docs") / "reference" / "plugins.md"

#: The command that regenerates the page (named in every "out of date" message).
COMMAND = "python tools/plugin_docs.py"

#: The base classes shown by the ``interfaces`` block, in this order.
INTERFACES: tuple[type, ...] = (
    interfaces.Strategy,
    interfaces.Parser,
    interfaces.Scorer,
    interfaces.Backend,
    interfaces.TransientBackendError,
    interfaces.PermanentBackendError,
)

_BEGIN = re.compile(r"^<!-- generated: (?P<what>[^>]*?) -->\n", re.MULTILINE)
_END = "<!-- end generated -->"

#: What each field of the documented models means: one short sentence per field.
FIELD_NOTES: dict[str, dict[str, str]] = {
    "Instance": {
        "house_id": "The house, e.g. `train_house_00003`.",
        "pair_id": "The (observer, anchor) pair within the house.",
        "direction": "`right`, `left`, `front` or `up`: where the target is from the speaker's point of view.",
        "condition": "`a` (Inferred), `b` (Stated) or `c` (Given): what the model is shown and told.",
        "sentence": "What the speaker said, the text the prompt carries.",
        "frames": "The frames shown: A/B the exploration frames in the official order; C one frame, the observer view.",
        "target": "The ground-truth 3D point (world frame, metres): what scorers project into a frame.",
        "observer_object": "The furniture the speaker used (for markers, e.g. `o-plot`).",
        "anchor_object": "The object the sentence names as the reference (for markers).",
        "observer_camera": "The speaker's camera (the Given view's camera).",
        "question": "The multiple-choice question asked (`ChoiceQuestion`: question, labelled options, gold label, category), or `None` for the point task.",
        "answer_type": "The answer type the instance asks for (`point` unless its loader says otherwise; `choice` for an instance carrying a `question`); a "
                       "strategy asking another is refused at load.",
        "numeric": "The numerical question the instance asks (`NumericQuestion`: question, gold number, unit, category; VSI-Bench's numerical types), or "
                   "`None`; it then asks for a `number`.",
    },
    "Frame": {
        "index": "Position in `Instance.frames`: what an answer's `selected_image` names.",
        "image_path": "The frame's path relative to the house folder; predictions name frames by it.",
        "file": "Where the image is on disk (add it to the run's `ImageStore` with `images.add_file(frame.file)`).",
        "camera": "The camera the frame was taken from (`width`, `height`, pose, field of view).",
        "in_frame_hits": "The objectIds the renderer saw in the frame (empty for an observer view).",
    },
    "Request": {
        "messages": "The chat messages, in order; images are `ImagePart`s naming a hash of the run's `ImageStore`.",
        "answer": "The `AnswerSpec`: what the model is asked to answer; the parser receives it.",
        "generation": "`GenerationParams`: `max_tokens`, `temperature`, extra settings.",
        "instance": "The instance the request is for: context for offline backends; never sent to a model.",
        "run": "The repeat index (seeded baselines read it); never sent, not part of the fingerprint.",
        "question": "A machine-readable sub-question of a multi-turn strategy; model backends ignore it.",
        "tools": "Functions the model may call (OpenAI function-calling schema, sent as litellm's `tools=`); empty for a plain request.",
    },
    "PlannedTurn": {
        "request": "The request as it will be sent, with `earlier_answer(turn)` placeholders where it carries the model's earlier answers.",
        "sent": "`False` for a turn the strategy works out itself (its final answer): shown, never sent, not counted as a request.",
        "note": "When the turn is taken if not always (e.g. `asked when turn 1 names an anchor`); empty when always.",
    },
    "Message": {
        "role": "`system`, `user`, `assistant` or `tool` (the result of one function call).",
        "parts": "`TextPart(text)` and `ImagePart(image_hash, label)` in the order the model sees them.",
        "tool_calls": "An assistant message's function calls (`ToolCall(id, name, arguments)`, arguments as sent).",
        "tool_call_id": "A `tool` message: the id of the call it answers.",
    },
    "GenerationParams": {
        "max_tokens": "New-token budget; `None` sends no limit.",
        "temperature": "Sampling temperature; `None` leaves the backend's default.",
        "extra": "Further `(name, value)` settings passed to the backend as they are.",
    },
    "Response": {
        "text": "The model's raw answer: what the parser reads.",
        "usage": "`Usage`: token counts and cost, `None` where unknown.",
        "latency_s": "Seconds the call took (the runner measures it when the backend leaves 0).",
        "model": "The model that answered, as the provider names it.",
        "retries": "Set by the runner: attempts after the first.",
        "cached": "Set by the runner: the answer came from the response cache.",
        "by_strategy": "A multi-turn strategy worked this answer out itself (no model call).",
        "solved_point": "The 3D point such a strategy worked out (the agent returns it as its goal).",
        "tool_calls": "The function calls the model made (`ToolCall`s) when the request offered tools; never cached.",
    },
    "Usage": {
        "prompt_tokens": "Tokens read, or `None`.",
        "completion_tokens": "Tokens written, or `None`.",
        "cost_usd": "Cost in US dollars, or `None`.",
    },
    "AnswerSpec": {
        "json_schema": "JSON Schema of the requested answer (key `schema` in JSON): `{selected_image, x, y}` for A/B, `{x, y}` for C.",
        "width": "Frame width in pixels: x is on `[0, width-1]`.",
        "height": "Frame height in pixels: y is on `[0, height-1]`.",
        "n_frames": "Images shown (1 for C): `selected_image` is on `[0, n_frames-1]`.",
        "asks_frame": "Whether the answer names a frame (A/B) or not (C).",
        "choices": "A multiple-choice question's options as `(label, text)` pairs, in the order shown; empty for a point.",
    },
    "ParsedAnswer": {
        "status": "`ok`, `repaired`, `out_of_range` (all answers) or `unparseable` (a non-response).",
        "reason": "Why the parse failed or what was odd, in a few words (shown in reports).",
        "selected_image": "0-based index of the chosen frame (A/B); `None` for C or when missing.",
        "x": "Pixel column in the requested frame size, or `None`.",
        "y": "Pixel row in the requested frame size, or `None`.",
        "points": "Every point of a multi-point answer (the prediction is their centroid); else `None`.",
        "span": "The raw text the answer was read from.",
        "repair": "How the text was changed to read it (e.g. `rescaled 0-1000 -> pixels`), else `None`.",
        "camera": "The camera of the image answered in when it is no dataset frame (the active mode's views): it is scored there.",
        "choice": "The option label a multiple-choice answer chose, or `None`.",
        "path": "The floor positions `(x, z)` a navigate episode walked through, start first (its last is where the walk ended; `camera` what it saw there), "
                "or `None` (then not written).",
        "number": "The number a `number` answer gave, as its rule read it (NaN or infinite when the reply said so), or `None` (then not written).",
    },
    "OfficialScore": {
        "answered": "Whether the row counts as answered officially (a point, and for A/B a frame that was shown).",
        "l2": "The official normalized L2 (clamped to the frame, blind spot included); `None` when unanswered.",
        "l2_strict": "The strict variant: a ground truth behind or outside the scored frame counts as sqrt 2.",
        "gt_in_frame": "Whether the ground truth projects inside the scored frame.",
        "gt_behind": "Whether the ground truth is behind the scored frame's camera.",
        "gt_u": "The ground truth across the scored frame, as a fraction of its width (0.5 when behind the camera, as officially).",
        "gt_v": "The ground truth down the scored frame, as a fraction of its height (0.5 when behind the camera).",
        "reason": "Why the row is unanswered (e.g. `missing or unknown selected frame`), else empty.",
        "error_x": "The official signed error `clamp(x/W) - clamp(gt_u)` of the recorded point (a point list's first), which `mean_abs_x` averages; `None` "
                   "when unanswered.",
        "error_y": "The official signed error `clamp(y/H) - clamp(gt_v)` of the recorded point, which `mean_abs_y` averages; `None` when unanswered.",
    },
}


class PluginDocsError(ValueError):
    """The page or the code cannot be rendered (an unknown block, a field without a note)."""


# -- docstrings to Markdown -------------------------------------------------------------------------
_ROLE = re.compile(r":(?:class|func|meth|mod|data|attr|exc):`(~?)([^`]+)`")


def markdown(doc: str) -> str:
    """A reST docstring as Markdown: roles and double backquotes become code, ``::`` blocks fences."""
    text = _ROLE.sub(lambda m: f"`{m.group(2).rsplit('.', 1)[-1] if m.group(1) else m.group(2)}`", doc)
    text = re.sub(r"``([^`]+)``", r"`\1`", text)
    out: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.rstrip().endswith("::"):
            out.append(line.rstrip()[:-1])
            block: list[str] = []
            i += 1
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith(" ")):
                block.append(lines[i])
                i += 1
            while block and not block[-1].strip():
                block.pop()
            while block and not block[0].strip():
                block.pop(0)
            indent = min((len(b) - len(b.lstrip()) for b in block if b.strip()), default=0)
            out += ["", "```", *(b[indent:] for b in block), "```", ""]
            continue
        out.append(line)
        i += 1
    return "\n".join(out).strip()


def _doc(obj: object) -> str:
    return markdown(inspect.getdoc(obj) or "")


class _Written(str):
    """An annotation as written in the source (shown without the quotes of a string's repr)."""

    def __repr__(self) -> str:
        return str(self)


def _signature(func: Callable[..., Any], name: str | None = None) -> str:
    """``name(param: type = default, ...) -> type`` with annotations as the source writes them."""
    sig = inspect.signature(func)

    def written(annotation: Any) -> Any:
        return _Written(annotation) if isinstance(annotation, str) else annotation

    params = [p.replace(annotation=written(p.annotation)) for p in sig.parameters.values()]
    if func.__name__ == "__init__":  # shown as the class is called: no self, nothing returned
        sig = sig.replace(parameters=params[1:], return_annotation=inspect.Signature.empty)
    else:
        sig = sig.replace(parameters=params, return_annotation=written(sig.return_annotation))
    prefix = "async " if inspect.iscoroutinefunction(func) else ""
    return f"{prefix}{name or func.__name__}{sig}"


def _summary(obj: object) -> str:
    """The first paragraph of a docstring, on one line."""
    return " ".join(_doc(obj).split("\n\n")[0].split())


# -- blocks -----------------------------------------------------------------------------------------
def hookspec_names() -> list[str]:
    """Every hookspec of :mod:`povagent.hookspecs`, in the order the module defines them."""
    return [n for n, f in vars(hookspecs).items() if inspect.isfunction(f) and hasattr(f, "povagent_spec")]


def render_hooks() -> str:
    """Every hookspec: its signature, how its results are combined, and its docstring."""
    parts = []
    for name in hookspec_names():
        func = getattr(hookspecs, name)
        opts = getattr(func, "povagent_spec", {}) or {}
        calls = (
            "The first non-`None` result wins (`firstresult`)."
            if opts.get("firstresult")
            else "Every plugin's implementation is called; return values are ignored."
        )
        parts.append(f"### `{name}`\n\n```python\n{_signature(func)}\n```\n\n{_doc(func)}\n\n*{calls}*")
    return "\n\n".join(parts)


def render_interfaces() -> str:
    """Each base class of :data:`INTERFACES`: its docstring and every public method's signature
    and docstring, the abstract ones marked *required*."""
    parts = []
    for cls in INTERFACES:
        bases = ", ".join(b.__name__ for b in cls.__bases__ if b is not object)
        section = [f"### `{cls.__name__}({bases})`", "", _doc(cls)]
        members = [n for n in vars(cls) if not n.startswith("_") or (n == "__init__" and issubclass(cls, Exception))]
        for name in members:
            member = vars(cls)[name]
            if isinstance(member, (staticmethod, classmethod)):
                member = member.__func__
            if not inspect.isfunction(member):
                if not name.startswith("_") and not callable(member) and cls.__annotations__.get(name):
                    section += ["", f"- `{name}: {cls.__annotations__[name]}` (class attribute, default `{member!r}`)"]
                continue
            required = " *(required)*" if getattr(member, "__isabstractmethod__", False) else ""
            shown = cls.__name__ if name == "__init__" else name
            section += ["", f"#### `{cls.__name__}.{name}`{required}" if name != "__init__" else f"#### `{cls.__name__}(...)`",
                        "", f"```python\n{_signature(member, shown)}\n```"]
            doc = _doc(member) if name != "__init__" else ""
            if doc:
                section += ["", doc]
        parts.append("\n".join(section))
    return "\n\n".join(parts)


def _model_fields(cls: type) -> list[tuple[str, str, str]]:
    """``(name, type as written, default)`` of each field of a dataclass or pydantic model."""
    rows = []
    if dataclasses.is_dataclass(cls):
        for f in dataclasses.fields(cls):
            if f.default is not dataclasses.MISSING:
                default = f"`{f.default!r}`"
            elif f.default_factory is not dataclasses.MISSING:
                default = f"`{getattr(f.default_factory, '__name__', 'factory')}()`"
            else:
                default = "required"
            rows.append((f.name, str(f.type), default))
        return rows
    if isinstance(cls, type) and issubclass(cls, BaseModel):
        written: dict[str, Any] = {}
        for klass in reversed(cls.__mro__):
            written.update(getattr(klass, "__annotations__", {}))
        for name, info in cls.model_fields.items():
            if info.default is not PydanticUndefined:
                default = f"`{info.default!r}`"
            elif info.default_factory is not None:
                default = f"`{getattr(info.default_factory, '__name__', 'factory')}()`"
            else:
                default = "required"
            rows.append((name, str(written.get(name, info.annotation)), default))
        return rows
    raise PluginDocsError(f"{cls.__qualname__} is neither a dataclass nor a pydantic model")


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def render_fields(target: str) -> str:
    """The field table of ``module:Class`` with the meanings of :data:`FIELD_NOTES`, then the
    class's public properties and methods with the first line of each docstring."""
    module_name, _, class_name = target.partition(":")
    try:
        cls = getattr(importlib.import_module(module_name), class_name)
    except (ImportError, AttributeError) as exc:
        raise PluginDocsError(f"fields {target}: no such class ({exc})") from None
    notes = FIELD_NOTES.get(class_name, {})
    fields = _model_fields(cls)
    missing = [n for n, _, _ in fields if n not in notes]
    stale = sorted(set(notes) - {n for n, _, _ in fields})
    if missing or stale:
        raise PluginDocsError(
            f"fields {target}: FIELD_NOTES[{class_name!r}] in tools/plugin_docs.py must describe exactly the fields of "
            f"{class_name}; fields without a note: {missing or 'none'}; notes for no field: {stale or 'none'}"
        )
    lines = [f"`{module_name}.{class_name}`: {_summary(cls)}", "",
             "| field | type | default | meaning |", "|---|---|---|---|"]
    lines += [f"| `{n}` | `{_cell(t)}` | {_cell(d)} | {_cell(notes[n])} |" for n, t, d in fields]
    extras = []
    for name, member in vars(cls).items():
        if name.startswith("_") or name in notes:
            continue
        func = member.fget if isinstance(member, property) else member
        if isinstance(func, (classmethod, staticmethod)):
            func = func.__func__
        if not inspect.isfunction(func):
            continue
        first = _summary(func)
        shown = f"`{name}`" if isinstance(member, property) else f"`{name}()`"
        extras.append(f"- {shown}: {first}")
    if extras:
        lines += ["", "Also:", "", *extras]
    return "\n".join(lines)


def render_include(relative: str, page: Path) -> str:
    """The file at ``relative`` (from the page's folder) as a fenced code block."""
    path = (page.parent / relative).resolve()
    if not path.is_file():
        raise PluginDocsError(f"{page}: include {relative}: no such file ({path})")
    language = {".py": "python", ".yaml": "yaml", ".yml": "yaml", ".toml": "toml"}.get(path.suffix, "")
    return f"```{language}\n{path.read_text(encoding='utf-8').rstrip()}\n```"


def render_parsers() -> str:
    """The built-in parsers' table: what each reads (its ``reads``) and how that compares with
    the official reading (its ``beside_official``), the official ones first. A parser without
    the two attributes shows its registration's description."""
    from povagent.plugins import build_plugin_host
    from povagent.results.official_reading import official_counterpart

    entries = [e for e in build_plugin_host(strict=False).entries("parser") if e.source.startswith("built-in ")]
    rows = sorted(((official_counterpart(e.factory()) is not None, e.name, e.factory) for e in entries), key=lambda r: (r[0], r[1]))
    lines = ["| parser | reads | compared with `official` |", "|---|---|---|"]
    for _, name, factory in rows:
        reads = getattr(factory, "reads", "") or _summary(factory)
        lines.append(f"| `{name}` | {_cell(reads)} | {_cell(getattr(factory, 'beside_official', ''))} |")
    return "\n".join(lines)


def render_tools() -> str:
    """The built-in active-mode tools' table, in the order an episode offers them: each tool's
    arguments (from its schema) and what it does (its ``explained``)."""
    from povagent.plugins import build_plugin_host

    host = build_plugin_host(strict=False, entry_points=False)
    lines = ["| tool | arguments | what it does |", "|---|---|---|"]
    for name, tool in host.tools(None).tools.items():
        arguments = ", ".join(f"{k}: {v.get('type', 'any')}" for k, v in tool.parameters.items())
        lines.append(f"| `{name}` | {f'`{arguments}`' if arguments else 'none'} | {_cell(tool.explained)} |")
    return "\n".join(lines)


def render_block(what: str, page: Path) -> str:
    """The content of one ``<!-- generated: WHAT -->`` block."""
    kind, _, argument = what.strip().partition(" ")
    if kind == "hooks" and not argument:
        return render_hooks()
    if kind == "interfaces" and not argument:
        return render_interfaces()
    if kind == "fields" and argument:
        return render_fields(argument.strip())
    if kind == "include" and argument:
        return render_include(argument.strip(), page)
    if kind == "parsers" and not argument:
        return render_parsers()
    if kind == "tools" and not argument:
        return render_tools()
    raise PluginDocsError(f"{page}: unknown generated block {what!r}; known: hooks, interfaces, fields MODULE:CLASS, include PATH, parsers, tools")


def render_page(text: str, page: Path) -> str:
    """``text`` (the page) with every generated block filled in from the code."""
    out: list[str] = []
    position = 0
    for match in _BEGIN.finditer(text):
        if match.start() < position:
            continue  # a begin marker inside a block being replaced
        end = text.find(_END, match.end())
        if end < 0:
            line = text.count("\n", 0, match.start()) + 1
            raise PluginDocsError(f"{page}:{line}: '<!-- generated: {match['what']} -->' has no '{_END}' after it")
        out += [text[position : match.end()], render_block(match["what"], page), "\n"]
        position = end
    out.append(text[position:])
    return "".join(out)


def check_page(page: Path = DEFAULT_PAGE) -> str | None:
    """``None`` when ``page`` is up to date with the code, else a message saying what to run."""
    text = page.read_text(encoding="utf-8")
    if render_page(text, page) == text:
        return None
    # the command names the page: the bare command rewrites only the default page
    command = COMMAND if _shown(page) == str(DEFAULT_PAGE) else f"{COMMAND} {_shown(page)}"
    return f"{page} is out of date with the code (hookspecs, interfaces, models or examples): run `{command}` and commit it"


def _shown(page: Path) -> str:
    """``page`` relative to the repository root when it is inside it (how the command is run)."""
    root = Path(__file__).resolve().parents[1]
    try:
        return str(page.resolve().relative_to(root))
    except ValueError:
        return str(page)


def main(argv: list[str] | None = None) -> int:
    """``python tools/plugin_docs.py [PAGE] [--check]``: rewrite the page's generated blocks."""
    parser = argparse.ArgumentParser(prog=COMMAND, description="Fill in the generated blocks of docs/reference/plugins.md from the code.")
    parser.add_argument("page", nargs="?", type=Path, default=DEFAULT_PAGE, help=f"the page (default: {DEFAULT_PAGE})")
    parser.add_argument("--check", action="store_true", help="only say whether the page is up to date (exit 1 if not)")
    args = parser.parse_args(argv)
    page: Path = args.page
    if not page.is_file():
        print(f"{page}: no such file (run from the repository root, or name the page)", file=sys.stderr)
        return 2
    try:
        if args.check:
            problem = check_page(page)
            print(problem or f"{page}: up to date", file=sys.stderr if problem else sys.stdout)
            return 1 if problem else 0
        text = page.read_text(encoding="utf-8")
        rendered = render_page(text, page)
    except PluginDocsError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if rendered != text:
        page.write_text(rendered, encoding="utf-8")
        print(f"{page}: generated blocks rewritten")
    else:
        print(f"{page}: up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main())
