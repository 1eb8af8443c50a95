"""The paper's future-work tasks on povagent's own generated houses (its Limitations, second).

POVBench frames its task "solely as image-space localization; relation classification,
multi-hop inference, and navigation are left to future work". Each task here turns a loaded
set's point instances into instances of another question, from the same houses, pairs and
conditions, with ground truth exact from the generator's geometry:

* :mod:`povagent.tasks.relation`: "From where the speaker stood, where is the X relative to
  the Y?", the registry's directions as options;
* :mod:`povagent.tasks.multi_hop`: the same relation reached through an intermediate object,
  answered as a point (the official metric) or a choice;
* :mod:`povagent.tasks.task_set`: a set whose instances are a task's (what the runner, rescore
  and show-prompt read when a pipeline names ``task:``).

What this package must not do: change a point instance (the point task is the loaded set
itself), or read anything but the dataset folder the pipeline names.
"""
