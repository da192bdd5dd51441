"""The noise keywords (docs/explanation/noise.md): `noise=` and
`temperature=` reach the CLI's validation and closed forms, and `Params`
carries them."""

from __future__ import annotations

import pytest

import irtp

RPT = "rpt:sigma=1,alpha=1,beta=2"


def test_analytic_runs_a_noise_model():
    res = irtp.analytic(drag="linear", noise=RPT, temperature=0.25, rate=0.5)
    assert res.summary["noise"] == RPT and res.summary["temperature"] == 0.25
    # rpt at r = 0, T = 0: D_eff = <v^2> (1/gamma + 1/alpha), docs/equations.md (N6).
    r0 = irtp.analytic(drag="linear", noise=RPT)
    assert r0.d_eff == pytest.approx(r0.v2 * 2.0, rel=1e-12)


def test_the_papers_noise_as_a_spec_is_the_same_numbers():
    a = irtp.analytic(drag="tanh", sigma=0.75, lambda_=0.625, points=20)
    b = irtp.analytic(drag="tanh", noise="telegraph:sigma=0.75,lambda=0.625", points=20)
    assert list(a.p) == list(b.p) and a.v2 == b.v2


@pytest.mark.parametrize("kwargs, name", [
    ({"noise": RPT, "temperature": 0.5}, "temperature"),
    ({"temperature": 0.5}, "temperature"),
])
def test_other_methods_refuse_a_noise_by_name(kwargs, name):
    # The exact first-passage sampler runs any finite-state noise at
    # temperature 0 only (no exact flow with thermal noise).
    with pytest.raises(ValueError) as e:
        irtp.mfpt(v0=0.0, vt=0.5, rate=1.0, method="exact", particles=10, **kwargs)
    assert str(e.value).startswith(f"invalid {name} = ")


def test_exact_first_passage_runs_a_noise_model():
    # Exact particles started in a state drawn from the noise's stationary
    # law (docs/equations.md (N46)-(N48)) against the backward equations'
    # pi-averaged tau: within 4 standard errors.
    b = irtp.mfpt(v0=0.0, vt=0.5, rate=1.0, noise=RPT, drag="tan")
    e = irtp.mfpt(v0=0.0, vt=0.5, rate=1.0, noise=RPT, drag="tan", method="exact",
                  particles=20000, seed=3)
    assert abs(e.tau - b.tau) < 4.0 * e.tau_err


def test_backward_and_euler_first_passage_run_a_noise_model():
    # N coupled backward equations (docs/equations.md (N30)-(N36)) against
    # Euler particles at dt and dt/2, extrapolated: within 4 standard errors.
    b = irtp.mfpt(v0=0.0, vt=0.5, rate=1.0, noise=RPT, drag="tan")
    runs = [irtp.mfpt(v0=0.0, vt=0.5, rate=1.0, noise=RPT, drag="tan", method="euler",
                      dt=dt, particles=4000, seed=s) for dt, s in [(2e-3, 1), (1e-3, 2)]]
    tau = 2.0 * runs[1].tau - runs[0].tau
    se = (4.0 * runs[1].tau_err ** 2 + runs[0].tau_err ** 2) ** 0.5
    assert abs(tau - b.tau) < 4.0 * se


def test_fp_stationary_runs_a_noise_model():
    # The N-state Fokker-Planck solver (docs/equations.md (N20)-(N29)).
    res = irtp.fp_stationary(cells=100, noise=RPT, temperature=0.1, drag="tan")
    assert res.summary["levels"] == [1.0, 0.0, -1.0]
    assert 0.0 < res.v2 < 1.0


def test_params_carry_noise_and_temperature():
    p = irtp.Params(drag="linear", noise=RPT, temperature=0.25)
    assert (p.noise, p.temperature) == (RPT, 0.25)
    res = irtp.analytic(params=p)
    assert res.summary["noise"] == RPT
    # A mapping with a noise spec drops sigma and lambda (the spec has them).
    back = irtp.Params.from_mapping({"drag": "linear", "noise": RPT, "temperature": 0.25,
                                     "sigma": 1.0, "lambda": 0.0, "rate": 0.0})
    assert (back.noise, back.sigma, back.lambda_) == (RPT, None, None)
    assert irtp.analytic(params=back).d_eff == res.d_eff


def test_the_noise_class_writes_the_spec_the_cli_takes():
    n = irtp.Noise.rpt(sigma=1, alpha=1, beta=2)
    assert str(n) == RPT and n.kind == "rpt" and n == RPT
    assert irtp.Noise.telegraph(1.5, 0.5).spec == "telegraph:sigma=1.5,lambda=0.5"
    asym = irtp.Noise.telegraph(plus=1.5, minus=0.75, rate_plus=0.8, rate_minus=0.4)
    assert asym.spec == "telegraph:plus=1.5,minus=0.75,rate_plus=0.8,rate_minus=0.4"
    three = irtp.Noise.states([1, 0, -1], [[-1, 1, 0], [0.5, -1, 0.5], [0, 1, -1]])
    assert three.spec == "states:levels=[1,0,-1],rates=[[-1,1,0],[0.5,-1,0.5],[0,1,-1]]"
    assert irtp.Noise.none().spec == "none"
    with pytest.raises(ValueError):
        irtp.Noise.telegraph(1.0)
    # Accepted wherever a spec is, with the same result.
    a = irtp.analytic(drag="linear", noise=n, temperature=0.25)
    b = irtp.analytic(drag="linear", noise=RPT, temperature=0.25)
    assert a.v2 == b.v2
    assert irtp.Params(drag="linear", noise=n).options()["noise"] == RPT
