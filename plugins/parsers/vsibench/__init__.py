"""VSI-Bench's answer rules, one module per reading: the set's own (:mod:`.official`) and
lmms-eval's (:mod:`.lmms`), each a registered parser reading both of the set's answer types
(an option letter for its multiple-choice questions, a number for its numerical ones)."""
