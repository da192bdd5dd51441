"""Result objects (repr, to_dict, to_pandas, params, provenance), model
objects, keyword handling, progress reporting, signatures and docstrings."""

from __future__ import annotations

import inspect
import json
import math
import pydoc

import numpy as np
import pytest

import irtp
from irtp import _irtp
from conftest import difference, same_bits, strip

SIM = dict(particles=200, t_max=3.0, samples=7, burn_in=1.0, bins=12)


def test_repr_shows_command_method_numbers_and_shapes():
    res = irtp.simulate(**SIM)
    text = repr(res)
    assert "irtp.simulate" in text and "'exact'" in text and "seed=1" in text
    assert "v2 = " in text and "moments [7]" in text and "density [12]" in text
    text = repr(irtp.mfpt_optimize(v0=-0.249, vt=0.5, cells=400, grid_points=9))
    assert "r_opt = " in text and "rate_grid" in text


def test_params_and_provenance_are_run_json():
    res = irtp.simulate(seed=11, **SIM)
    prov = res.provenance
    for key in ("software", "version", "command", "argv", "method", "seed", "parameters",
                "wall_time_s", "threads"):
        assert key in prov, key
    assert prov["software"] == "irtp" and prov["version"] == irtp.__version__
    assert prov["command"] == "simulate" and prov["seed"] == 11 == res.seed
    assert prov["parameters"] == res.params
    assert res.params["particles"] == 200 and res.params["model"]["sigma"] == 3.0
    assert res.method == prov["method"] == "exact"
    assert isinstance(res.text, str) and res.text
    assert res.out is None and res.files is None


def test_to_dict():
    res = irtp.fp_stationary(cells=200)
    d = res.to_dict()
    assert set(d) == {"command", "method", "seed", "summary", "params", "provenance",
                      "tables", "text", "out", "files"}
    assert d["tables"]["density"]["p"] is res.p
    plain = res.to_dict(lists=True)
    assert plain["tables"]["density"]["p"] == res.p.tolist()
    json.dumps(plain)


def test_to_pandas():
    pd = pytest.importorskip("pandas")
    sim = irtp.simulate(**SIM)
    frames = sim.to_pandas()
    assert set(frames) == {"moments", "density"}
    assert list(frames["moments"].columns) == list(sim.tables["moments"])
    assert np.array_equal(frames["density"]["p"].to_numpy(), sim.p)
    fp = irtp.fp_stationary(cells=200).to_pandas()
    assert isinstance(fp, pd.DataFrame) and len(fp) == 200
    exact = irtp.mfpt(v0=-0.249, vt=0.5, method="exact", particles=50).to_pandas()
    assert list(exact.columns) == ["t", "survival", "survival_err", "at_risk"]
    assert exact["survival"].iloc[0] == 1.0 and exact["survival"].iloc[-1] == 0.0
    assert len(sim.to_pandas("moments")) == 7


def test_model_objects_equal_plain_keywords():
    plain = irtp.fp_stationary(drag="tanh", sigma=0.6, lambda_=0.85, rate=1.0,
                               reset_velocity=0.1, cells=200)
    model = irtp.Params(drag=irtp.Drag("tanh"), sigma=0.6, lambda_=0.85,
                        reset=irtp.PoissonReset(1.0, velocity=0.1))
    for res in (irtp.fp_stationary(params=model, cells=200),
                irtp.fp_stationary(params=irtp.Params(sigma=0.6, lambda_=0.85), cells=200,
                                   drag=irtp.Drag("tanh"),
                                   reset=irtp.PoissonReset(1.0, 0.1)),
                irtp.fp_stationary(params=plain.params["model"], cells=200),
                irtp.fp_stationary(params=plain.summary["params"], cells=200),
                irtp.fp_stationary(cells=200, drag="tanh", sigma=0.6, rate=1.0,
                                   reset_velocity=0.1, **{"lambda": 0.85})):
        assert difference(strip(res.summary), strip(plain.summary)) is None
        assert same_bits(res.p, plain.p)
    assert irtp.Params.from_mapping(plain.params["model"]) == model
    assert model.reset == irtp.PoissonReset(1.0, 0.1)
    assert model.replace(sigma=0.5).sigma == 0.5 and model.sigma == 0.6
    assert "lambda_=0.85" in repr(model)


def test_params_fill_only_what_they_set():
    # analytic has rate 0 by default and no reset_velocity: a Params without
    # a rate, or with v_r = 0, works there as well.
    res = irtp.analytic(params=irtp.Params(drag="tan", sigma=3.0, lambda_=0.9), points=11)
    assert res.summary["lambda"] == 0.9 and res.summary["rate"] == 0.0
    res = irtp.analytic(params=irtp.Params(lambda_=0.9, reset=irtp.PoissonReset(0.0)),
                        points=11)
    assert res.summary["rate"] == 0.0
    res = irtp.analytic(lambda_=0.9, reset=irtp.PoissonReset(0.0), points=11)
    assert res.summary["rate"] == 0.0
    with pytest.raises(ValueError, match="reset_velocity"):
        irtp.analytic(params=irtp.Params(reset=irtp.PoissonReset(0.0, velocity=0.3)))


def test_ode_is_the_former_name_of_backward():
    a = irtp.mfpt(v0=-0.249, vt=0.5, cells=500, method="backward")
    with pytest.warns(FutureWarning, match="former name"):
        b = irtp.mfpt(v0=-0.249, vt=0.5, cells=500, method="ode")
    assert difference(strip(a.summary), strip(b.summary)) is None
    assert a.summary["method"] == "backward"


def test_progress_callable_sees_monotone_counts():
    calls = []
    irtp.simulate(particles=4000, t_max=20.0, samples=5, burn_in=1.0, bins=8,
                  progress=lambda label, done, total: calls.append((label, done, total)))
    assert calls, "progress was never called"
    labels = {c[0] for c in calls}
    assert labels == {"simulate"}
    done = [c[1] for c in calls]
    assert done == sorted(done)
    assert all(0 <= d <= t for _, d, t in calls)
    assert calls[-1][1] == calls[-1][2]


def test_progress_true_without_tqdm_writes_a_line(monkeypatch, capsys):
    import irtp._progress as progress

    monkeypatch.setattr(progress, "_tqdm", lambda: None)
    irtp.fp_transient(t_max=0.5, scheme="paper", cells=100, progress=True)
    err = capsys.readouterr().err
    assert "fp transient" in err and err.endswith("\n")
    assert " time steps (100%)" in err, "the bar names its unit"


def test_progress_estimate_waits_for_enough_work():
    from irtp._progress import time_left, unit_of

    assert time_left(10.0, 0.25) == 30.0
    assert time_left(10.0, 0.01) is None and time_left(0.5, 0.5) is None
    assert unit_of("simulate") == "particles" and unit_of("fig7") == "%"


def test_signature_defaults_come_from_the_cli_definitions():
    for function, command in irtp._api.COMMANDS.items():
        sig = inspect.signature(getattr(irtp, function))
        options = _irtp.describe(command)
        names = [("lambda_" if d["name"] == "lambda" else "from_" if d["name"] == "from"
                  else d["name"]) for d in options]
        assert [n for n in sig.parameters if n in names] == names
        assert {"progress", "threads"} <= set(sig.parameters)
        for d, name in zip(options, names):
            p = sig.parameters[name]
            if d["kind"] == "list":
                assert p.kind == p.VAR_POSITIONAL
                continue
            assert p.kind == p.KEYWORD_ONLY
            if d["required"]:
                assert p.default is p.empty, name
            elif d["kind"] == "float" and d["default"] is not None:
                assert p.default == float(d["default"]), name
            elif d["kind"] == "int" and d["default"] is not None:
                assert p.default == int(d["default"]), name
            elif d["kind"] == "bool":
                assert p.default is False, name
    assert inspect.signature(irtp.simulate).parameters["sigma"].default == 3.0


def test_help_is_useful_on_its_own():
    text = pydoc.render_doc(irtp.simulate, renderer=pydoc.plaintext)
    for needle in ("burn_in", "lambda_", "default 0.5", "Eq. (5)", "Eqs. (30)-(32)",
                   "moments", "progress", "threads", "KeyboardInterrupt", "NumericalError"):
        assert needle in text, needle
    for function, command in irtp._api.COMMANDS.items():
        doc = getattr(irtp, function).__doc__
        assert "Eq" in doc and "Parameters" in doc and "Examples" in doc
        for d in _irtp.describe(command):
            first = d["help"].split("--")[0].split()[:3]
            assert " ".join(first) in " ".join(doc.split()), (function, d["name"])
    assert "from_" in irtp.mfpt_scan.__doc__ and "'backward'" in irtp.mfpt.__doc__


def test_version(cli, tmp_path):
    """The module and the CLI name the version and git revision that
    provenance records."""
    assert irtp.__version__ == _irtp.__version__
    res = irtp.analytic(points=11, out=str(tmp_path / "a"))
    prov = res.provenance
    assert (prov["version"], prov.get("git_revision")) == (irtp.__version__, irtp.__git_revision__)
    line = cli.run(["--version"]).stdout.strip()
    if irtp.__git_revision__ is None:
        assert line.startswith(f"irtp {irtp.__version__} (no git revision")
    else:
        assert line == f"irtp {irtp.__version__} (git {irtp.__git_revision__})"


def test_nan_free_summary_numbers():
    res = irtp.mfpt_optimize(v0=-0.249, vt=0.5, cells=400, grid_points=9)
    assert math.isfinite(res.r_opt) and res.interior in (True, False)


def test_censored_mfpt_withholds_tau_and_gives_the_bound():
    res = irtp.mfpt(v0=0.0, vt=0.5, rate=60.0, t_max=1.0, method="exact", particles=2000)
    assert res.tau is None and res.summary["tau"] is None and res.tau_err is None
    assert 0 < res.censored < res.particles
    assert res.censored_fraction == res.censored / res.particles
    assert res.tau_lower_bound == res.rmst and 0 < res.rmst <= 1.0 and res.rmst_err > 0
    assert isinstance(res.survival, np.ndarray) and res.survival.dtype == np.float64
    assert res.t[0] == 0.0 and res.t[-1] == 1.0 and res.at_risk[-1] == res.censored
    assert res.survival is res.tables["survival"]["survival"]
    assert "tau_lower_bound = " in repr(res) and res.text.startswith("CENSORED: ")
    ok = irtp.mfpt(v0=-0.249, vt=0.5, method="exact", particles=500)
    assert ok.censored == 0 and ok.tau_lower_bound is None and ok.rmst == ok.tau
    assert ok.survival[-1] == 0.0
