"""The element converges at second order in h on a standing P wave with a closed form."""

import pytest

from pdfem.tools.study.convergence import observed_orders


@pytest.mark.parametrize("rule", ["1pt", "2x2"])
def test_observed_order_is_two(rule):
    result = observed_orders(sizes=(8, 16), rules=(rule,))[rule]
    assert 1.7 <= result["order"] <= 2.3
    # Small errors on the finer mesh: the comparison is with the right solution
    assert result["runs"][-1]["error"] < 0.05
