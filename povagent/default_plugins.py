"""The built-in plugins, loaded exactly like third-party ones (by module name).

Each entry is a module of ``povagent_plugins`` (the repository's ``plugins/`` folder) that
implements ``register_*`` hooks. Keep one module per line, grouped by kind.
"""

DEFAULT_PLUGINS: tuple[str, ...] = (
    # answer types
    "povagent_plugins.answers.point",
    "povagent_plugins.answers.choice",
    "povagent_plugins.answers.walk",
    "povagent_plugins.answers.number",
    "povagent_plugins.answers.choice_or_number",
    # dataset formats
    "povagent_plugins.formats.povbench",
    "povagent_plugins.formats.realworld",
    "povagent_plugins.formats.viewspatial",
    "povagent_plugins.formats.mindcube",
    "povagent_plugins.formats.srbench3d",
    "povagent_plugins.formats.mmsi",
    "povagent_plugins.formats.omnispatial",
    "povagent_plugins.formats.vsibench",
    # scorers
    "povagent_plugins.scorers.official",
    "povagent_plugins.scorers.success",
    "povagent_plugins.scorers.diagnose",
    "povagent_plugins.scorers.relation",
    "povagent_plugins.scorers.probe",
    "povagent_plugins.scorers.choice",
    "povagent_plugins.scorers.navigate",
    "povagent_plugins.scorers.choice_vlmevalkit",
    "povagent_plugins.scorers.choice_sparbench",
    "povagent_plugins.scorers.srbench3d",
    "povagent_plugins.scorers.choice_mindcube",
    "povagent_plugins.scorers.vsibench",
    # parsers
    "povagent_plugins.parsers.official",
    "povagent_plugins.parsers.json_answer",
    "povagent_plugins.parsers.cot",
    "povagent_plugins.parsers.rescale",
    "povagent_plugins.parsers.qwen",
    "povagent_plugins.parsers.gemini",
    "povagent_plugins.parsers.molmo",
    "povagent_plugins.parsers.robopoint",
    "povagent_plugins.parsers.internvl",
    "povagent_plugins.parsers.choice",
    "povagent_plugins.parsers.mcq.viewspatial",
    "povagent_plugins.parsers.mcq.mindcube",
    "povagent_plugins.parsers.mcq.threedsrbench",
    "povagent_plugins.parsers.mcq.vlmevalkit_exact",
    "povagent_plugins.parsers.mcq.vlmevalkit_spatial",
    "povagent_plugins.parsers.mcq.lmms_mcq_extract",
    "povagent_plugins.parsers.mcq.sparbench",
    "povagent_plugins.parsers.mcq.mmsi",
    "povagent_plugins.parsers.mcq.omnispatial",
    "povagent_plugins.parsers.vsibench.official",
    "povagent_plugins.parsers.vsibench.lmms",
    # strategies
    "povagent_plugins.strategies.basic",
    "povagent_plugins.strategies.cot",
    "povagent_plugins.strategies.markers",
    "povagent_plugins.strategies.geometric",
    "povagent_plugins.strategies.probes",
    "povagent_plugins.strategies.active",
    "povagent_plugins.strategies.navigate",
    "povagent_plugins.strategies.choice",
    "povagent_plugins.strategies.choice_or_number",
    # backends
    "povagent_plugins.backends.litellm_backend",
    "povagent_plugins.backends.transformers_backend",
    "povagent_plugins.backends.baselines",
    "povagent_plugins.backends.replay",
    "povagent_plugins.backends.simulated",
    "povagent_plugins.backends.planted",
    "povagent_plugins.backends.explorers",
    "povagent_plugins.backends.human",
    # active-mode tools (offered in this order)
    "povagent_plugins.tools.go_to_frame",
    "povagent_plugins.tools.turn",
    "povagent_plugins.tools.tilt",
    "povagent_plugins.tools.move",
    "povagent_plugins.tools.ask",
    "povagent_plugins.tools.answer",
    "povagent_plugins.tools.arrived",
    # model profiles
    "povagent_plugins.backends.profiles",
    # surface judges (the dataset generator's stage 3)
    "povagent_plugins.judges.physical_rules",
)
