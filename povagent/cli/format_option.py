"""``--format``: a registered dataset format, its help listing the formats the plugins register.

The list is read from the plugin host when the help is shown (:class:`FormatsInHelp`), not when
the command line starts: loading every plugin takes seconds, and most commands never show help.
"""

from __future__ import annotations

from typing import Any

import typer
from typer.core import TyperCommand, TyperOption

#: What ``--format``'s help says before the registered formats are listed.
FORMAT_HELP = "The set's dataset format (a registered one; default: the folder's own, read as the runner reads it)."


def format_option(help: str = FORMAT_HELP) -> Any:
    """``--format FORMAT``: a dataset format's key; the command's help lists the registered ones
    when the command is declared with ``cls=FormatsInHelp``."""
    return typer.Option(None, "--format", metavar="FORMAT", help=help)


def registered_format_keys() -> list[str]:
    """The keys of every registered dataset format (plugins that fail to load are left out:
    ``povagent plugins`` names them)."""
    from povagent.plugins import build_plugin_host

    return build_plugin_host(strict=False).names("format")


class FormatsInHelp(TyperCommand):
    """A command whose ``--format`` help ends with the registered formats, read as it is shown."""

    def format_help(self, ctx: Any, formatter: Any) -> None:
        """The usual help, ``--format``'s listing every registered format."""
        for param in self.params:
            if isinstance(param, TyperOption) and "--format" in param.opts:
                base = (param.help or "").split(" Registered:")[0]
                param.help = f"{base} Registered: {', '.join(registered_format_keys())}."
        super().format_help(ctx, formatter)
