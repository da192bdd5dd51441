"""Bad input raises the right exception with the CLI's message, naming the
keyword instead of the flag; nothing is written."""

from __future__ import annotations

import math

import pytest

import irtp
from irtp import _irtp


def test_sigma_message_is_the_cli_message(cli):
    with pytest.raises(ValueError) as e:
        irtp.simulate(sigma=-1, particles=10)
    expected = cli.error(["simulate", "--sigma", "-1", "--particles", "10"])
    assert str(e.value) == expected.replace("--sigma", "sigma")
    assert "sigma" in str(e.value) and "--" not in str(e.value)


def test_lambda_message_names_the_python_keyword(cli):
    with pytest.raises(ValueError) as e:
        irtp.fp_stationary(lambda_=-1, cells=100)
    expected = cli.error(["fp", "stationary", "--lambda", "-1", "--cells", "100"])
    assert str(e.value) == expected.replace("--lambda", "lambda_")
    assert "lambda_" in str(e.value)


def test_from_message_names_the_python_keyword():
    with pytest.raises(ValueError, match="from_"):
        irtp.mfpt_scan(v0=-0.249, vt=0.5, over="rate", from_=0.0, to=1.0, log=True)


@pytest.mark.parametrize("function", ["simulate", "fp_stationary", "mfpt", "analytic"])
def test_unknown_keyword(function):
    with pytest.raises(ValueError) as e:
        getattr(irtp, function)(sigmaa=1.0)
    msg = str(e.value)
    assert "unknown keyword 'sigmaa'" in msg and f"irtp.{function}" in msg
    assert "sigma" in msg.split("known:")[1]


def test_positional_arguments_are_refused():
    with pytest.raises(TypeError):
        irtp.simulate(1000)


def test_missing_required_keyword():
    with pytest.raises(TypeError, match="v0"):
        irtp.mfpt(vt=0.5)
    with pytest.raises(TypeError, match="t_max"):
        irtp.fp_transient()


def test_keyword_given_twice():
    with pytest.raises(ValueError, match="sigma given twice"):
        irtp.fp_stationary(params=irtp.Params(sigma=2.0), sigma=3.0, cells=100)
    with pytest.raises(ValueError, match="lambda_ given twice"):
        irtp.fp_stationary(lambda_=0.5, cells=100, **{"lambda": 0.7})
    with pytest.raises(ValueError, match="rate given twice"):
        irtp.fp_stationary(reset=irtp.PoissonReset(1.0), rate=2.0, cells=100)
    with pytest.raises(ValueError, match="rate given twice"):
        irtp.fp_stationary(reset=irtp.PoissonReset(1.0), params=irtp.Params(rate=1.0))
    with pytest.raises(ValueError, match="drag given twice"):
        irtp.fp_stationary(drag=irtp.Drag("tanh"), params=irtp.Params(drag="tan"))
    with pytest.raises(ValueError, match="rate given twice"):
        irtp.Params(reset=irtp.PoissonReset(1.0), rate=2.0)


def test_unknown_drag_law_lists_the_known_ones():
    known = [d["name"] for d in _irtp.drag_laws()]
    for call in (lambda: irtp.Drag("foo"), lambda: irtp.fp_stationary(drag="foo"),
                 lambda: irtp.Params(drag="foo")):
        with pytest.raises(ValueError) as e:
            call()
        assert "'foo'" in str(e.value)
        assert all(name in str(e.value) for name in known)


def test_drag_objects():
    tan, tanh = irtp.Drag("tan"), irtp.Drag("tanh")
    assert tan.force_limit == math.inf and tanh.force_limit == 1.0
    assert "thickening" in tan.description and "thinning" in tanh.description
    assert tan == "tan" and tan == irtp.Drag(tan) and repr(tan) == "Drag('tan')"
    assert [d.name for d in irtp.drag_laws()] == [d["name"] for d in _irtp.drag_laws()]


def test_range_errors_name_the_keyword():
    with pytest.raises(ValueError, match="sigma"):
        irtp.fp_stationary(drag="tanh", sigma=2.0, cells=100)
    with pytest.raises(ValueError, match="rate"):
        irtp.analytic(rate=1.0)
    with pytest.raises(ValueError, match="dt"):
        irtp.simulate(dt=0.01, particles=10)
    with pytest.raises(ValueError, match="vt"):
        irtp.mfpt_scan(v0=-0.249, over="rate", from_=0.1, to=1.0)
    with pytest.raises(ValueError, match="cells"):
        irtp.fp_stationary(cells=1)


def test_bad_choice_lists_the_choices():
    with pytest.raises(ValueError) as e:
        irtp.mfpt(v0=-0.249, vt=0.5, method="rk4")
    assert all(m in str(e.value) for m in ("ode", "exact", "euler", "backward"))


def test_nothing_is_written_on_bad_input(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(ValueError):
        irtp.simulate(sigma=-1.0, out=out)
    with pytest.raises(ValueError):
        irtp.mfpt(v0=-0.249, vt=5.0, out=out)
    assert list(tmp_path.iterdir()) == []


def test_numerical_error_is_a_runtime_error():
    assert irtp.NumericalError is _irtp.NumericalError
    assert issubclass(irtp.NumericalError, RuntimeError)


def test_bad_progress_argument():
    with pytest.raises(TypeError, match="progress"):
        irtp.fp_stationary(cells=100, progress="yes")


def test_parameterised_drag_specs_pass_through():
    res = irtp.analytic(drag="power:n=0.5", sigma=3.0, lambda_=0.9)
    assert res.summary["drag"] == "power:n=0.5,k=1"
    d = irtp.Drag("carreau:n=0.5,a=2")
    assert d.law == "carreau" and d.name == "carreau:n=0.5,a=2" and d.force_limit == math.inf
    for spec, key in [("power:n=-1", "n > 0"), ("carreau:n=0.5,a=0", "a > 0"),
                      ("power:n=0.5,q=1", "'q'")]:
        with pytest.raises(ValueError, match=key):
            irtp.analytic(drag=spec, sigma=3.0, lambda_=0.9)


def test_expression_drag_passes_through():
    res = irtp.fp_stationary(drag="expr:v  +  v^3/3", sigma=3.0, rate=2.0, cells=500)
    assert res.params["model"]["drag"] == "expr:v + v^3/3"
    ref = irtp.fp_stationary(drag="cubic", sigma=3.0, rate=2.0, cells=500)
    assert abs(res.summary["v2"] - ref.summary["v2"]) <= 1e-9 * ref.summary["v2"]
    assert irtp.Drag("expr:sinh(v)").law == "expr"
    for spec, needle in [("expr:v^2", "not odd"), ("expr:foo(v)", "unknown name 'foo'")]:
        with pytest.raises(ValueError, match=needle):
            irtp.fp_stationary(drag=spec, sigma=3.0, cells=500)
    with pytest.raises(ValueError, match="sigma"):
        irtp.fp_stationary(drag="expr:tanh(v)", sigma=3.0, cells=500)


@pytest.mark.parametrize("kw", [{"sigma": "3"}, {"lambda_": "0.5"}, {"particles": "100"}, {"seed": "7"}])
def test_strings_are_not_numbers(kw):
    (name, value), = kw.items()
    with pytest.raises(TypeError) as e:
        irtp.simulate(**{"particles": 100, **kw})
    msg = str(e.value)
    assert msg.startswith(f"{name} must be ") and repr(value) in msg, msg


def test_threads_are_bounded():
    with pytest.raises(ValueError, match=r"threads <= 1024"):
        irtp.simulate(particles=100, threads=10**6)
    with pytest.raises(ValueError, match=r"threads <= 1024"):
        _irtp.run("analytic", {}, threads=10**6)


def test_huge_expression_is_refused_not_a_crash():
    with pytest.raises(ValueError, match=r"at most 200"):
        irtp.analytic(drag="expr:" + "+".join(["v"] * 250))


def test_out_with_a_newline_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"control characters"):
        irtp.analytic(out=str(tmp_path / "a\nb"))
    assert list(tmp_path.iterdir()) == []
