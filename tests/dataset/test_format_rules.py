"""Every registered dataset format names an official rule that exists: its answer type, official
parser and official scorer are registered plugins, and the parser reads that answer type. A
format registered without its rule (a parser entry deleted, a name misspelt) fails here, not as
rows read by the wrong rule."""

from __future__ import annotations

from dataclasses import replace

import pytest

from povagent import hookimpl
from povagent.config.pipeline import load_pipeline
from povagent.dataset.formats import missing_rules, registered_formats
from povagent.errors import ConfigError
from povagent.plugins import build_plugin_host
from povagent_plugins.formats.viewspatial import VIEWSPATIAL

BUILT_IN = {"povbench", "generated", "realworld", "viewspatial", "mindcube", "3dsrbench"}


def test_every_registered_format_has_an_official_rule_that_exists():
    host = build_plugin_host()
    assert set(registered_formats(host)) >= BUILT_IN
    assert missing_rules(host) == []


def test_each_built_in_format_is_registered_by_its_own_plugin_module():
    host = build_plugin_host()
    sources = {key: host.entry("format", key).source for key in BUILT_IN}
    assert all(source.startswith("built-in povagent_plugins.formats.") for source in sources.values()), sources


def _plugin(fmt):
    class Plugin:
        @hookimpl
        def register_dataset_formats(self, register):
            register(fmt.key, fmt)

    return Plugin()


@pytest.mark.parametrize(
    ("change", "said"),
    [
        ({"official_parser": "myset-offical"}, "names parser 'myset-offical', which no plugin registers"),
        ({"official_scorer": "choice-myset"}, "names scorer 'choice-myset', which no plugin registers"),
        ({"answer_type": "nonesuch"}, "names answer_type 'nonesuch', which no plugin registers"),
        ({"official_parser": "official"}, "its official parser 'official' does not read 'choice' answers"),
    ],
    ids=["parser", "scorer", "answer type", "parser of another type"],
)
def test_a_format_without_its_official_rule_is_found(povagent_host, change, said):
    povagent_host.add_plugin(_plugin(replace(VIEWSPATIAL, key="myset", **change)), name="myset", source="plugin myset")
    try:
        assert missing_rules(povagent_host) == [f"dataset format 'myset' (plugin myset) {said}".replace("(plugin myset) its", "(plugin myset): its")]
    finally:
        povagent_host.remove_plugin("myset")


def test_a_pipeline_naming_a_format_without_its_rule_is_refused_at_the_format_line(tmp_path):
    plugin = tmp_path / "myset_format.py"
    plugin.write_text(
        "from dataclasses import replace\n"
        "from povagent import hookimpl\n"
        "from povagent_plugins.formats.viewspatial import VIEWSPATIAL\n"
        "MYSET = replace(VIEWSPATIAL, key='myset', official_parser='myset-official')\n"
        "@hookimpl\n"
        "def register_dataset_formats(register):\n"
        "    register('myset', MYSET)\n"
    )
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text("plugins: [myset_format.py]\ndataset:\n  path: set.json\n  format: myset\nbackend: center\noutput: runs/x\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(pipeline)
    assert (
        f"{pipeline}, line 4: dataset.format: dataset format 'myset' (config plugin {plugin}) names parser 'myset-official', which no plugin registers"
        in str(err.value)
    )
