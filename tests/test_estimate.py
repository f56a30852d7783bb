"""The converged estimate of a mesh ladder: Richardson extrapolation with the observed order
on ladders with a closed form, the bounds on the order, oscillating and two-level ladders, and
the rules combined."""

import math

import pytest

from pdfem.tools.study import estimate as est
from pdfem.tools.study.accuracy import Setting

LEVELS = [1, 2, 3, 4]


def ladder(q_inf, c, p, levels=LEVELS):
    """Values q_inf + c h^p at h = 1 / level: a ladder in its asymptotic range."""
    return [q_inf + c * (1.0 / lv) ** p for lv in levels]


@pytest.mark.parametrize("p", [0.7, 1.0, 1.5, 2.0])
def test_an_exact_power_law_is_extrapolated_to_its_limit(p):
    e = est.ladder_estimate(LEVELS, ladder(850.0, 100.0, p))
    assert e["order"] == pytest.approx(p, rel=1e-9)
    assert e["value"] == pytest.approx(850.0, rel=1e-12)
    # The band: 1.25 x the correction from the finest level, q(4) - q_inf = 100 / 4^p
    assert e["uncertainty"] == pytest.approx(1.25 * 100.0 / 4.0 ** p, rel=1e-9)
    assert e["levels"] == [2, 3, 4]


def test_the_order_is_held_within_its_bounds():
    # Faster than the formal order 2: extrapolated with 2 (a larger correction than p = 3's)
    fast = est.ladder_estimate(LEVELS, ladder(850.0, 100.0, 3.0))
    assert fast["order"] == pytest.approx(3.0) and fast["order_used"] == 2.0
    h2, h3, q3, q2 = 1 / 3, 1 / 4, 850.0 + 100 / 64, 850.0 + 100 / 27
    assert fast["value"] == pytest.approx(q3 + (q3 - q2) * h3 ** 2 / (h2 ** 2 - h3 ** 2))
    # Slower than 0.5: held at 0.5
    slow = est.ladder_estimate(LEVELS, ladder(850.0, 100.0, 0.2))
    assert slow["order"] == pytest.approx(0.2) and slow["order_used"] == 0.5
    # Differences that shrink more slowly than any positive order: order 0, used 0.5
    assert est.observed_order([1.0, 0.5, 1 / 3], [0.0, 1.0, 3.0]) == 0.0
    growing = est.ladder_estimate([1, 2, 3], [0.0, 1.0, 3.0])
    assert growing["order_used"] == 0.5 and growing["how"].startswith("differences not shrinking")


def test_an_oscillating_ladder_takes_the_middle_of_its_range():
    e = est.ladder_estimate(LEVELS, [3395.4, 3364.7, 3360.7, 3385.6])
    assert e["order"] is None and e["how"].startswith("oscillating")
    assert e["value"] == pytest.approx(0.5 * (3360.7 + 3385.6))
    assert e["uncertainty"] == pytest.approx(1.25 * 0.5 * (3385.6 - 3360.7))
    # A statistical error of the finest value adds 2 se in quadrature
    noisy = est.ladder_estimate(LEVELS, [3395.4, 3364.7, 3360.7, 3385.6], se=29.8)
    assert noisy["uncertainty"] == pytest.approx(math.hypot(e["uncertainty"], 59.6))


def test_two_levels_assume_order_two_with_a_wider_band():
    e = est.ladder_estimate([1, 2], [900.0, 860.0])
    # q_inf = q2 + (q2 - q1) h2^2 / (h1^2 - h2^2) = 860 - 40 / 3; band 3 x the correction
    assert e["value"] == pytest.approx(860.0 - 40.0 / 3.0)
    assert e["uncertainty"] == pytest.approx(40.0) and e["order"] is None
    # Missing values are left out; fewer than two points give no estimate
    assert est.ladder_estimate([1, 2, 3], [900.0, math.nan, 860.0])["levels"] == [1, 3]
    assert est.ladder_estimate([1, 2], [900.0, math.nan]) is None
    # The same value on the last three levels: exact
    same = est.ladder_estimate(LEVELS, [900.0, 850.0, 850.0, 850.0])
    assert (same["value"], same["uncertainty"]) == (850.0, 0.0)


def test_rules_that_agree_are_averaged_and_rules_that_disagree_are_flagged():
    a = {"value": 100.0, "uncertainty": 4.0}
    b = {"value": 103.0, "uncertainty": 2.0}
    c = est.combine({"1pt": a, "2x2": b})
    # Inverse-variance mean: weights 1/16 and 1/4
    assert c["agree"] and c["value"] == pytest.approx((100 / 16 + 103 / 4) / (1 / 16 + 1 / 4))
    assert c["uncertainty"] == pytest.approx(1.0 / math.sqrt(1 / 16 + 1 / 4))
    far = est.combine({"1pt": a, "2x2": {"value": 110.0, "uncertainty": 2.0}})
    assert not far["agree"] and far["value"] == 105.0 and far["uncertainty"] == 9.0
    one = est.combine({"1pt": None, "2x2": b})
    assert one["rules"] == ["2x2"] and (one["value"], one["uncertainty"]) == (103.0, 2.0)
    assert est.combine({"1pt": None}) is None


def test_the_estimate_of_a_study_grid_uses_each_rules_ladder():
    def row(level, rule, us, status="ok", axis="grid"):
        return {"setting": Setting(level, rule, 0.5, 1.0, axis), "status": status,
                "us": us, "us_se": 1.0}

    rows = [row(lv, "2x2", q) for lv, q in zip(LEVELS, ladder(850.0, 100.0, 1.0), strict=True)]
    rows += [row(lv, "1pt", q) for lv, q in zip(LEVELS, ladder(850.0, -40.0, 2.0), strict=True)]
    # Runs off the grid, or that failed, are not part of a ladder
    rows += [row(4, "2x2", 0.0, axis="safety"), row(5, "1pt", 0.0, status="failed: x")]
    out = est.converged(rows, ["us"], {"us": "us_se"})["us"]
    assert out["rules"]["2x2"]["value"] == pytest.approx(850.0)
    assert out["rules"]["1pt"]["value"] == pytest.approx(850.0)
    # Each band holds its finest run's 2 se
    assert out["rules"]["2x2"]["uncertainty"] == pytest.approx(math.hypot(1.25 * 25.0, 2.0))
    assert out["combined"]["agree"] and out["combined"]["value"] == pytest.approx(850.0)
