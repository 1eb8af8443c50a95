"""The official POVBench metric and the summaries built on it (pure functions)."""
