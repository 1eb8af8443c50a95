"""Sphinx configuration of the povagent documentation (furo theme, MyST Markdown).

Build: ``pip install '.[docs]' && sphinx-build -W -b html docs docs/_build``. The reference pages
for the CLI, the YAML schema, the file formats and the model profiles are written from the code
when the build starts (``_ext/reference_pages.py``); warnings are errors, so a broken internal
link or a page missing from every toctree fails the build.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))

project = "povagent"
author = "the povagent authors"
copyright = "the povagent authors"

extensions = ["myst_parser", "reference_pages"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_ext", "Thumbs.db", ".DS_Store"]

# GitHub-style anchors on headings down to ###, so `page.md#a-heading` links resolve
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence", "deflist"]
# a code block the highlighter cannot colour (a ```mermaid diagram, JSON with an elision "...")
# is shown as plain text: cosmetic, so not an error; every other warning is
suppress_warnings = ["misc.highlighting_failure"]

html_theme = "furo"
html_title = "povagent"

# the link check follows only internal links: nothing here reaches the internet
linkcheck_ignore = [r"https?://.*"]
