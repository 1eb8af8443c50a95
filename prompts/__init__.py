"""Prompt templates, installed as ``povagent_prompts``: one file per prompt, placeholders named.

Read them with :func:`povagent.exchange.prompts.load_template`, never by path, so they work from a wheel.
"""
