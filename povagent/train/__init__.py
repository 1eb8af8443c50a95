"""Training sets for observer grounding, made from POVBench-format datasets.

What it is for: turning houses (generated or the release) into supervised fine-tuning rows in
the formats trainers read (Hugging Face Parquet shards, chat-message JSONL), with reasoning
traces computed from the scene's geometry, never written by a model. What it must not do: put
an evaluation house in a training set, or state a fact the geometry does not support.
"""
