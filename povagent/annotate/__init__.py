"""``povagent annotate``: a local web page where a person answers as a system (answer mode).

The person answers through the ``human`` backend, so every answer is a row the runner writes
like a model's (:mod:`povagent.run`); this package only carries questions from the runner to
the page and answers back (:mod:`~povagent.annotate.desk`), orders the instances for one
annotator (:mod:`~povagent.annotate.order`) and serves the page safely
(:mod:`~povagent.annotate.server`). It never writes a run folder itself.
"""
