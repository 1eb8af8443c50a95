"""``python -m povagent.cli``: the same as the ``povagent`` console script."""

from povagent.cli import main

main()
