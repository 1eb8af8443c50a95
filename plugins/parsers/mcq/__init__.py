"""The field's multiple-choice rules, one module per rule family, each a registered parser.

Each parser reproduces one upstream rule at a pinned commit (named in its description and in
:mod:`.upstream`), bugs included, so a score read with it equals the harness's own; where a rule
is known to read a wrong answer as right, a ``-corrected`` parser sits beside it. The rules are
re-implemented from the upstream code, never copied. The shared piece, lmms-eval's removal of
reasoning blocks, lives in :mod:`.lmms_reasoning`.
"""
