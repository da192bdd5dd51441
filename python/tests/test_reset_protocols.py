"""Resetting protocols from Python: the keywords reset_noise and reset_to,
the spec recorded in the parameters, and Params round trips."""

from __future__ import annotations

import pytest

import irtp


def test_redrawn_protocol_round_trips_through_params():
    r = irtp.fp_stationary(drag="linear", sigma=1.0, rate=2.0, reset_velocity=0.2,
                           reset_noise="redrawn", cells=2000)
    model = r.params["model"]
    assert model["reset"] == "point:v=0.2,noise=redrawn"
    p = irtp.Params.from_mapping(model)
    assert p.reset_to == "point:v=0.2,noise=redrawn"
    again = irtp.fp_stationary(params=p, cells=2000)
    assert again.summary["d_eff"] == r.summary["d_eff"]
    # D_eff = (Var v + <v eta>/(2 lambda + r)) / (1 + r) for linear drag.
    ve = 1.0 / (1 + 1.0 + 2.0)
    m = 2.0 * 0.2 / 3.0
    v2 = (2 * ve + 2.0 * 0.04) / 4.0
    d = (v2 - m * m + ve / (1.0 + 2.0)) / 3.0
    assert abs(r.summary["d_eff"] / d - 1) < 1e-5


def test_random_target_spec_and_bad_input():
    r = irtp.fp_stationary(reset_to="gauss:mean=0,std=0.3", cells=2000)
    assert r.params["model"]["reset"] == "gauss:mean=0,std=0.3,noise=kept"
    with pytest.raises(ValueError, match="reset_to"):
        irtp.fp_stationary(reset_to="gauss:mean=5,std=0.3")
    # mfpt optimize runs a random target too (the backward equations'
    # target weights) and an exponential refractory period (a Markov hold);
    # a fixed one (not Markov in (v, noise)) is refused, naming the flag.
    opt = irtp.mfpt_optimize(v0=-0.249, vt=0.5, reset_to="uniform:a=-0.5,b=0.2")
    assert opt.params["problem"]["params"]["reset"] == "uniform:a=-0.5,b=0.2,noise=kept"
    assert opt.params["tau_opt"] <= opt.params["tau_r0"]
    held = irtp.mfpt_optimize(v0=-0.249, vt=0.5, refractory="exp:mean=0.2")
    assert held.params["problem"]["params"]["refractory"] == "exp:mean=0.2"
    assert held.params["tau_opt"] <= held.params["tau_r0"]
    with pytest.raises(ValueError, match="refractory"):
        irtp.mfpt_optimize(v0=-0.249, vt=0.5, refractory="fixed:t=0.2")
