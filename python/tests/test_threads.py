"""Results are bit-identical for 1 and 2 threads (particles are reduced in
fixed chunks in index order)."""

from __future__ import annotations

import pytest

import irtp
from conftest import difference, same_bits, strip

CASES = [
    ("simulate", dict(particles=3000, t_max=4.0, samples=9, burn_in=1.0, bins=16)),
    ("simulate", dict(particles=600, t_max=1.0, samples=5, burn_in=0.5, bins=8,
                      method="euler", dt=0.002)),
    ("mfpt", dict(v0=-0.249, vt=0.5, method="exact", particles=3000)),
    ("mfpt", dict(v0=-0.249, vt=0.5, method="euler", particles=300)),
    ("mfpt_scan", dict(v0=-0.249, vt=0.5, over="rate", from_=0.5, to=2.0, points=3,
                       method="exact", particles=1000, cells=500)),
    ("fp_stationary", dict(cells=2000)),
]


@pytest.mark.parametrize("function,kwargs", CASES, ids=[c[0] for c in CASES])
def test_one_and_two_threads_identical(function, kwargs):
    one = getattr(irtp, function)(threads=1, **kwargs)
    two = getattr(irtp, function)(threads=2, **kwargs)
    assert difference(strip(one.summary), strip(two.summary)) is None
    assert list(one.tables) == list(two.tables)
    for name, table in one.tables.items():
        for col, values in table.items():
            assert same_bits(values, two.tables[name][col]), (name, col)
    assert one.provenance.get("threads") == 1
    assert two.provenance.get("threads") == 2


def test_threads_must_be_positive():
    with pytest.raises(ValueError, match="threads"):
        irtp.fp_stationary(cells=100, threads=0)
