"""Which run the report's gallery draws, said on the page when a system ran more than once.

The gallery draws each system's first run (:func:`povagent.report.gallery.select_rows`), while
the tables average every run; this sentence keeps a reader from taking the cards for all runs.
Pure: reads observations, writes nothing.
"""

from __future__ import annotations

from typing import Any, Iterable


def run_shown_note(observations: Iterable[Any], systems: list[str]) -> str:
    """The sentence saying which run the gallery draws, when a system ran more than once
    (the gallery shows each system's first run; a reader must not take it for all of them)."""
    runs: dict[str, set[int]] = {s: set() for s in systems}
    for o in observations:
        if o.system in runs:
            runs[o.system].add(o.run)
    repeated = {s: sorted(r) for s, r in runs.items() if len(r) > 1}
    if not repeated:
        return ""
    firsts = sorted({r[0] for r in repeated.values()})
    counts = sorted({len(r) for r in repeated.values()})
    first = f"run {firsts[0]}" if len(firsts) == 1 else "its first run"
    of = f"{counts[0]} runs" if len(counts) == 1 else "its runs"
    return (
        f"The gallery draws one run per system: {first} of {of} ({', '.join(repeated)}). "
        "The tables above average every run."
    )
