"""Imports run downward: every room of povagent stands on a floor, and the few imports that run
back up (from a room to one on a higher floor) are the ones the architecture page names, with why.

The floors are read from the architecture page's "Floors" section (ground floor last, as a
building is drawn); a room is a folder of ``povagent/`` (``run/``), a module at its top
(``errors.py``, ``povagent/__init__.py`` as ``__init__.py``) or the built-in plugins
(``plugins/``). An arrow is a pair of rooms, however many import lines it carries, so one new
upward import from an unlisted pair fails here. Imports count wherever they are written (a
function body, ``TYPE_CHECKING``), as in ``test_import_cycles``; the scan reads the source.

``python tests/test_import_floors.py`` prints every upward arrow with its import lines.
"""

from __future__ import annotations

import re

from test_import_cycles import ROOT, povagent_import_edges

ARCHITECTURE = ROOT / "docs" / "explanation" / "architecture.md"
#: At most this many pairs of rooms may import upward (issue 56).
MAX_ARROWS_UP = 11

Arrow = tuple[str, str]


def room_of(module: str) -> str:
    """The room a dotted module name stands in: ``run/``, ``errors.py``, ``plugins/``."""
    parts = module.split(".")
    if parts[0] == "povagent_plugins":
        return "plugins/"
    if len(parts) == 1:
        return "__init__.py"
    sub = ROOT / "povagent" / parts[1]
    return f"{parts[1]}/" if sub.is_dir() else f"{parts[1]}.py"


def section(title: str, text: str) -> str:
    """The body of the section of ``text`` whose heading starts with ``title``."""
    match = re.search(rf"^#+ {re.escape(title)}[^\n]*\n(.*?)(?=^#+ |\Z)", text, flags=re.M | re.S)
    assert match, f"{ARCHITECTURE.name} has no section {title!r}"
    return match.group(1)


def documented_floors(text: str) -> dict[str, int]:
    """Room -> floor from the "Floors" section's drawing: lines ``N  room  room ...``."""
    drawing = re.search(r"```\n(.*?)```", section("Floors", text), flags=re.S)
    assert drawing, "the Floors section draws its floors in a ``` block"
    floors: dict[str, int] = {}
    for line in drawing.group(1).splitlines():
        number, _, rooms = line.strip().partition(" ")
        for room in re.findall(r"\S+(?:/|\.py)(?=\s|$)", rooms):
            assert room not in floors, f"{room} stands on two floors"
            floors[room] = int(number)
    return floors


def documented_arrows(text: str) -> set[Arrow]:
    """The arrows the "Arrows that run back up" section names: ``- `a/` → `b/`: why``."""
    return set(re.findall(r"^- `([^`]+)` → `([^`]+)`: \S", section("Arrows that run back up", text), flags=re.M))


def room_imports() -> dict[Arrow, list[str]]:
    """Every import between two rooms, ``(importer room, imported room) -> ["a -> b", ...]``
    (the tree is read once a process, however many tests ask)."""
    found: dict[Arrow, list[str]] = {}
    for a, b in sorted(povagent_import_edges()[1]):
        if room_of(a) != room_of(b):
            found.setdefault((room_of(a), room_of(b)), []).append(f"{a} -> {b}")
    return found


def arrows_up(floors: dict[str, int], imports: dict[Arrow, list[str]]) -> dict[Arrow, list[str]]:
    """The pairs of rooms where the importer stands on a lower floor than what it imports."""
    return {(a, b): lines for (a, b), lines in imports.items() if floors[a] < floors[b]}


def test_a_room_on_a_lower_floor_importing_a_higher_one_is_an_arrow_up():
    floors = {"errors.py": 0, "files/": 1, "run/": 2}
    imports = {("files/", "errors.py"): ["x"], ("files/", "run/"): ["povagent.files.a -> povagent.run.b"]}
    assert arrows_up(floors, imports) == {("files/", "run/"): ["povagent.files.a -> povagent.run.b"]}


def test_the_floors_and_arrows_are_read_from_the_page():
    text = "## Floors\n```\n2  run/  report/\n1  files/\n0  errors.py\n```\n### Arrows that run back up\n- `files/` → `run/`: because.\n"
    assert documented_floors(text) == {"run/": 2, "report/": 2, "files/": 1, "errors.py": 0}
    assert documented_arrows(text) == {("files/", "run/")}


def test_every_room_stands_on_exactly_one_floor():
    floors = documented_floors(ARCHITECTURE.read_text(encoding="utf-8"))
    rooms = {room for pair in room_imports() for room in pair}
    assert sorted(rooms - set(floors)) == [] and sorted(set(floors) - rooms) == []


def test_rooms_on_one_floor_do_not_import_each_other():
    floors = documented_floors(ARCHITECTURE.read_text(encoding="utf-8"))
    assert [pair for pair in room_imports() if floors[pair[0]] == floors[pair[1]]] == []


def test_the_ground_floor_imports_nothing_above_it():
    floors = documented_floors(ARCHITECTURE.read_text(encoding="utf-8"))
    ground = {room for room, floor in floors.items() if floor <= floors["files/"]}
    assert [pair for pair in room_imports() if pair[0] in ground and pair[1] not in ground] == []


def test_only_the_named_arrows_run_back_up_and_at_most_eleven():
    text = ARCHITECTURE.read_text(encoding="utf-8")
    up = arrows_up(documented_floors(text), room_imports())
    unnamed = {pair: lines for pair, lines in up.items() if pair not in documented_arrows(text)}
    assert unnamed == {}, "import(s) running back up that the architecture page does not name (move the helper down, or name the arrow and why)"
    assert sorted(documented_arrows(text) - set(up)) == [], "named arrows that no longer run up: remove them from the page"
    assert len(up) <= MAX_ARROWS_UP


if __name__ == "__main__":
    text = ARCHITECTURE.read_text(encoding="utf-8")
    up = arrows_up(documented_floors(text), room_imports())
    for (a, b), lines in sorted(up.items(), key=lambda item: documented_floors(text)[item[0][0]]):
        print(f"{a} -> {b}  ({len(lines)} import(s)): " + "; ".join(lines))
    print(f"{len(up)} arrows up, {sum(map(len, up.values()))} import lines")
