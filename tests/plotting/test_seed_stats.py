"""Per-seed summaries (simlunar.plotting.seed_stats)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simlunar.plotting import tables
from simlunar.plotting.seed_stats import _seed_summary, seed_summary_numbers, t_interval


def test_t_interval_by_hand():
    # [1, 2, 3]: mean 2, s = 1, t(0.975, 2) = 4.302653 -> half width 4.302653 / sqrt(3) = 2.48414
    m, lo, hi = t_interval([1.0, 2.0, 3.0])
    assert m == 2.0
    assert lo == pytest.approx(2.0 - 2.484138, abs=1e-6)
    assert hi == pytest.approx(2.0 + 2.484138, abs=1e-6)
    with pytest.raises(ValueError, match="at least two"):
        t_interval([1.0])


def test_seed_summary_numbers_geometric_mean_in_log_space():
    # ratios 1, e, e^2: log mean 1 -> geometric mean e; NaN and 0 are left out
    m, lo, hi, n = seed_summary_numbers([1.0, math.e, math.e**2, math.nan, 0.0], log=True)
    assert n == 3 and m == pytest.approx(math.e)
    _, llo, lhi = t_interval([0.0, 1.0, 2.0])
    assert (lo, hi) == (pytest.approx(math.exp(llo)), pytest.approx(math.exp(lhi)))
    assert seed_summary_numbers([4.0], log=False)[::3] == (4.0, 1)
    assert seed_summary_numbers([math.nan], log=False)[3] == 0


def test_seed_summary_cells_count_the_seeds_left_out():
    mean, rng = _seed_summary(np.array([1.0, 2.0, 3.0, np.nan]), log=False)
    assert mean.startswith("2.00 [") and rng == "1.00–3.00 (3 of 4 seeds)"
    assert _seed_summary(np.array([np.nan]), log=False) == ("–", "(0 of 1 seeds)")
    assert _seed_summary(np.array([5.0]), log=True) == ("5.00", "")


def test_tables_re_exports_the_summaries():
    assert tables.t_interval is t_interval and tables.seed_summary_numbers is seed_summary_numbers
