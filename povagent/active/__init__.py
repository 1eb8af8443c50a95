"""Active observer grounding: a generated house as an environment a model acts in.

What it is for: the paper's passive evaluation shows fixed frames; here a model may look
around a povagent-generated house (go to an exploration frame, turn, tilt, move, ask the
speaker) before it answers, through ordinary tool calls. This room holds the environment:
the house rebuilt from its record and rendered byte-exactly (:mod:`.house`), poses and moves
against the reachable floor (:mod:`.pose`, :mod:`.floor`), the simulated speaker
(:mod:`.speaker`), the tool schema and the checking of calls (:mod:`.tools`), the episode
with its budget (:mod:`.episode`), its record (:mod:`.record`) and the content-addressed view
folder (:mod:`.views`). What it must not do: call a model or know the runner; only the
``active`` strategy, the explorer backends, the ``render`` command and the report (which reads
views by the store's rule) import it.

The package imports nothing itself: the renderer (embree, the generator) loads only when a
house is rebuilt (``povagent.active.house.render_view``), never when the plugin list is read.
"""
