"""The report aggregates runs as the paper does (mean of per-run means); pooled is labelled."""

from __future__ import annotations

import pytest

from povagent.report.analysis import pooled_official
from povagent.report.collect import Observation
from povagent.report.statistics import cell_stats


def obs(run, iid, l2):
    return Observation(
        system="m", run_name="r", run=run, instance_id=iid, house_id="h", pair_id="p", direction="left",
        condition="a", status="answered", parse_status="ok", answered=l2 is not None, l2=l2, l2_strict=l2,
        gt_in_frame=True, gt_behind=False, gt_u=0.5, gt_v=0.5, selected_image=0, image_path=None, x=1.0, y=1.0,
        sentence="s", raw="{}",
    )


# run 0 answers one instance of two; run 1 answers all four (a different instance set per run)
OBS = [obs(0, "i0", 0.1), obs(0, "i1", None)] + [obs(1, f"i{k}", 0.3) for k in range(4)]


def test_the_official_cell_is_the_mean_of_per_run_means():
    cs = cell_stats(OBS, n_boot=0)
    assert cs.official.value == pytest.approx((0.1 + 0.3) / 2)
    assert cs.response_rate.value == pytest.approx((0.5 + 1.0) / 2)


def test_pooled_numbers_are_kept_and_labelled():
    pooled = pooled_official(OBS)
    assert pooled["aggregation"] == "pooled"
    assert pooled["overall"]["mean_l2"] == pytest.approx((0.1 + 4 * 0.3) / 5)
    assert pooled["per_condition"]["a"]["n_total"] == 6
