"""The resetting-rule modifiers from Python: reset_period, reset_clock,
reset_position and refractory as keywords and as Params fields, recorded in the parameters,
refused by name where a method does not run them."""

from __future__ import annotations

import pytest

import irtp


def test_modifiers_are_recorded_and_round_trip():
    r = irtp.simulate(particles=2000, t_max=8.0, burn_in=2.0, reset_position=0.5,
                      refractory="exp:mean=0.2", seed=3)
    model = r.params["model"]
    assert model["reset_position"] == 0.5
    assert model["refractory"] == "exp:mean=0.2"
    p = irtp.Params.from_mapping(model)
    assert (p.reset_position, p.refractory) == (0.5, "exp:mean=0.2")
    again = irtp.simulate(params=p, particles=2000, t_max=8.0, burn_in=2.0, seed=3)
    assert again.summary["v2"] == r.summary["v2"]


def test_periodic_clock_and_fp_refractory_mass():
    # The window [2, 8] holds six periods of 1.
    r = irtp.simulate(particles=2000, t_max=8.0, burn_in=2.0, reset_period=1.0, seed=5)
    assert r.params["model"]["reset_period"] == 1.0
    fp = irtp.fp_stationary(drag="linear", sigma=1.0, rate=1.5, refractory="exp:mean=0.4",
                            cells=2000)
    # Held mass r M / (1 + r M).
    assert abs(fp.summary["refractory_mass"] - 0.6 / 1.6) < 1e-9


def test_bad_modifiers_are_refused_by_name():
    with pytest.raises(ValueError, match="reset_period"):
        irtp.simulate(reset_period=0.0)
    with pytest.raises(ValueError, match="refractory"):
        irtp.simulate(refractory="exp:mean=-1")
    with pytest.raises(ValueError, match="rate"):
        irtp.simulate(reset_period=1.0, rate=2.0)
    # fp stationary has no stationary state to give under a periodic clock.
    with pytest.raises(ValueError, match="reset_period"):
        irtp.fp_stationary(reset_period=1.0)
    with pytest.raises(ValueError, match="unknown keyword"):
        irtp.Params(reset_every=1.0)


def test_renewal_clock_keyword_is_recorded_and_refused_by_name():
    r = irtp.simulate(particles=2000, t_max=8.0, burn_in=2.0,
                      reset_clock="gamma:k=2,theta=0.5", seed=7)
    model = r.params["model"]
    assert model["reset_clock"] == "gamma:k=2,theta=0.5"
    p = irtp.Params.from_mapping(model)
    assert p.reset_clock == "gamma:k=2,theta=0.5"
    again = irtp.simulate(params=p, particles=2000, t_max=8.0, burn_in=2.0, seed=7)
    assert again.summary["v2"] == r.summary["v2"]
    with pytest.raises(ValueError, match="reset.clock"):
        irtp.simulate(reset_clock="gamma:k=0,theta=1")
    with pytest.raises(ValueError, match="reset.clock"):
        irtp.simulate(reset_clock="fixed:t=1", reset_period=1.0)
    with pytest.raises(ValueError, match="reset.clock"):
        irtp.fp_stationary(reset_clock="exp:rate=1")
