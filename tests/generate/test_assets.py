"""ProcTHOR's databases are read as files, with every category the paper uses."""

from __future__ import annotations

import subprocess
import sys

from povagent.generate.assets import OBSERVER_ANCHOR_CATEGORIES, asset_database


def test_all_31_observer_anchor_categories_have_real_assets():
    db = asset_database()
    assert len(OBSERVER_ANCHOR_CATEGORIES) == 31
    assert all(db[t] for t in OBSERVER_ANCHOR_CATEGORIES)
    bed = db["Bed"][0]
    assert 0.5 < bed.width < 2.5 and 0.2 < bed.height < 2.5


def test_reading_the_databases_never_imports_procthor_or_ai2thor():
    code = (
        "import sys; from povagent.generate.assets import asset_database, placement_annotations;"
        "asset_database(); placement_annotations();"
        "print(any(m.split('.')[0] in ('procthor', 'ai2thor') for m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
