"""Offline POVBench-format dataset generation."""
