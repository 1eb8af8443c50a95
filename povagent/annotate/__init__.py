"""``povagent annotate``: a local web page where a person answers as a system, or judges
runs' predictions by hand.

Answer mode: the person answers through the ``human`` backend, so every answer is a row the
runner writes like a model's (:mod:`povagent.run`); this package only carries questions from the
runner to the page and answers back (:mod:`~povagent.annotate.desk`), orders the instances for
one annotator (:mod:`~povagent.annotate.order`) and serves the page safely
(:mod:`~povagent.annotate.server`). It never writes a run folder itself.

Judge mode: the predictions of finished runs, shown blind (:mod:`~povagent.annotate.judge_page`),
each verdict a line of the judge's journalled file (:mod:`~povagent.results.judgements`), which
the report reads (:mod:`povagent.report.manual`).
"""
