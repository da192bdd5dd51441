"""Table columns are 1-D, C-contiguous float64 numpy arrays of the right
length, shared (not copied) between ``res.tables`` and the attributes."""

from __future__ import annotations

import numpy as np
import pytest

import irtp

CASES = [
    ("simulate", dict(particles=100, t_max=2.0, samples=13, burn_in=1.0, bins=17),
     {"moments": 13, "density": 17}),
    ("simulate", dict(particles=50, t_max=1.0, samples=7, burn_in=0.5, bins=9,
                      method="euler"), {"moments": 7, "density": 9}),
    ("analytic", dict(points=41), {"density": 41}),
    ("fp_stationary", dict(cells=300), {"density": 300}),
    ("fp_transient", dict(t_max=0.5, cells=120, samples=6, snapshots=3),
     {"moments": 6, "snapshots": 3 * 120}),
    ("mfpt", dict(v0=-0.249, vt=0.5, cells=400), {"profile": None}),
    ("mfpt", dict(v0=-0.249, vt=0.5, method="exact", particles=100), {"survival": None}),
    ("mfpt_scan", dict(v0=-0.249, vt=0.5, over="rate", from_=0.1, to=1.0, points=4,
                       cells=400), {"mfpt_scan": 4}),
    ("mfpt_optimize", dict(v0=-0.249, vt=0.5, cells=400, grid_points=9), {"rate_grid": None}),
]

COLUMNS = {
    ("simulate", "moments"): ["t", "v_mean", "v_mean_err", "v2", "v2_err", "x_mean",
                              "x_mean_err", "x2", "x2_err"],
    ("simulate", "density"): ["v", "p", "p_err", "p_final", "p_final_err"],
    ("analytic", "density"): ["v", "p", "cdf"],
    ("fp_stationary", "density"): ["v", "p", "p_plus", "p_minus", "dv"],
    ("fp_transient", "moments"): ["t", "v_mean", "v2", "mass"],
    ("fp_transient", "snapshots"): ["t", "v", "p", "p_plus", "p_minus"],
    ("mfpt", "profile"): ["v0", "tau", "tau_plus", "tau_minus"],
    ("mfpt", "survival"): ["t", "survival", "survival_err", "at_risk"],
    ("mfpt_scan", "mfpt_scan"): ["rate", "tau", "tau_plus", "tau_minus", "error_estimate"],
    ("mfpt_optimize", "rate_grid"): ["rate", "tau"],
}


@pytest.mark.parametrize("function,kwargs,rows", CASES, ids=[c[0] for c in CASES])
def test_columns_are_float64_arrays(function, kwargs, rows):
    res = getattr(irtp, function)(**kwargs)
    assert list(res.tables) == list(rows)
    for name, table in res.tables.items():
        assert list(table) == COLUMNS[(function, name)]
        lengths = set()
        for col, arr in table.items():
            assert isinstance(arr, np.ndarray), (name, col)
            assert arr.dtype == np.float64 and arr.ndim == 1, (name, col)
            assert arr.flags["C_CONTIGUOUS"], (name, col)
            lengths.add(arr.shape[0])
        assert len(lengths) == 1
        if rows[name] is not None:
            assert lengths == {rows[name]}
        else:
            assert lengths.pop() >= 2


def test_attributes_are_the_table_arrays():
    res = irtp.fp_transient(t_max=0.5, cells=100, samples=5, snapshots=2)
    assert res.t is res.tables["moments"]["t"]  # the first table wins
    assert res.v is res.tables["snapshots"]["v"]
    assert res.tables["snapshots"]["t"].shape == (200,)
    assert res.v2_final == res.summary["v2_final"]


def test_summary_scalars_shadowed_by_columns():
    res = irtp.simulate(particles=50, t_max=2.0, samples=5, burn_in=1.0, bins=8)
    assert isinstance(res.v2, np.ndarray)  # the moments column
    assert isinstance(res.summary["v2"], float)  # the stationary value
    assert res.d_eff_msd == res.summary["d_eff_msd"]
    assert res.particles == 50
    with pytest.raises(AttributeError, match="no_such"):
        res.no_such
    assert "x2" in dir(res) and "d_eff_msd" in dir(res)
