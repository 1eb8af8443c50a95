"""Reports: the paper's tables, statistics and the HTML report.

One module per step, in the order a report is made:

- :mod:`~povagent.report.collect`: run and sweep folders -> observations labelled by system;
- :mod:`~povagent.report.baseline`: the center baseline computed for the same instances;
- :mod:`~povagent.report.baseline_systems`: which systems are baselines (reference rows, not models);
- :mod:`~povagent.report.statistics`: means over runs, bootstrap CIs, paired tests;
- :mod:`~povagent.report.analysis`: every number of a report, per system and breakdown;
- :mod:`~povagent.report.tables` / :mod:`~povagent.report.paper_tables`: Markdown, CSV, LaTeX;
- :mod:`~povagent.report.plots` / :mod:`~povagent.report.figures`: inline SVG plots;
- :mod:`~povagent.report.gallery`: predictions drawn on their frames, named by hash;
- :mod:`~povagent.report.html`: the self-contained page; :mod:`~povagent.report.build` wires it;
- :mod:`~povagent.report.compare` (two runs) and :mod:`~povagent.report.export` (official rows).

Entry point for code: :func:`povagent.report.build.write_report`.
"""
