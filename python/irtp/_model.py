"""Model pieces as small Python objects: the drag law, the reset rule and a
parameter set. They only carry values; the Rust side validates them (one
home for every rule), so an invalid ``sigma`` is reported by the function
that runs, with the CLI's message.
"""

from __future__ import annotations

import numbers
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple

from . import _irtp

_LAWS: Optional[Dict[str, Dict[str, Any]]] = None


def _laws() -> Dict[str, Dict[str, Any]]:
    """The registry of the Rust crate, read once: ``{name: info}`` in CLI order."""
    global _LAWS
    if _LAWS is None:
        _LAWS = {d["name"]: dict(d) for d in _irtp.drag_laws()}
    return _LAWS


def _known_laws() -> str:
    return ", ".join(_laws())


class Noise:
    """An active noise eta(t) other than the paper's (docs/equations.md,
    "Noise kinds"): a finite-state Markov noise, written as the spec
    ``--noise`` takes. Accepted by every function as ``noise=`` (with
    ``temperature=`` adding thermal noise sqrt(2T) dW), and by
    :class:`Params`; a plain spec string works too. The Rust registry
    validates it when a function runs (a bad one is a ``ValueError`` naming
    ``noise``).

    >>> str(Noise.rpt(sigma=1, alpha=1, beta=2))
    'rpt:sigma=1,alpha=1,beta=2'
    >>> str(Noise.telegraph(plus=1.5, minus=0.75, rate_plus=0.8, rate_minus=0.4))
    'telegraph:plus=1.5,minus=0.75,rate_plus=0.8,rate_minus=0.4'
    >>> str(Noise.states([1, 0, -1], [[-1, 1, 0], [0.5, -1, 0.5], [0, 1, -1]]))
    'states:levels=[1,0,-1],rates=[[-1,1,0],[0.5,-1,0.5],[0,1,-1]]'

    Attributes
    ----------
    spec : str
        What ``--noise`` takes.
    kind : str
        The kind's name (``telegraph``, ``rpt``, ``states``, ``none``).
    """

    __slots__ = ("_spec",)

    def __init__(self, spec: "str | Noise") -> None:
        if isinstance(spec, Noise):
            spec = spec.spec
        if not isinstance(spec, str) or not spec.strip():
            raise ValueError(f"a noise spec must be a non-empty string, not {spec!r}")
        self._spec = spec

    @staticmethod
    def _num(x: float) -> str:
        x = float(x)
        return str(int(x)) if x.is_integer() and abs(x) < 1e15 else repr(x)

    @classmethod
    def telegraph(
        cls,
        sigma: "float | None" = None,
        lambda_: "float | None" = None,
        *,
        plus: "float | None" = None,
        minus: "float | None" = None,
        rate_plus: "float | None" = None,
        rate_minus: "float | None" = None,
    ) -> "Noise":
        """Two levels: ``telegraph(sigma, lambda_)`` (the paper's, ±sigma at
        rate lambda_) or ``telegraph(plus=P, minus=M, rate_plus=KP,
        rate_minus=KM)`` (+P and -M, leaving +P at rate KP and -M at KM)."""
        n = cls._num
        if sigma is not None or lambda_ is not None:
            if None in (sigma, lambda_) or any(
                v is not None for v in (plus, minus, rate_plus, rate_minus)
            ):
                raise ValueError("telegraph: give sigma and lambda_, or plus, minus, rate_plus, rate_minus")
            return cls(f"telegraph:sigma={n(sigma)},lambda={n(lambda_)}")
        if None in (plus, minus, rate_plus, rate_minus):
            raise ValueError("telegraph: give sigma and lambda_, or plus, minus, rate_plus, rate_minus")
        return cls(
            f"telegraph:plus={n(plus)},minus={n(minus)},"
            f"rate_plus={n(rate_plus)},rate_minus={n(rate_minus)}"
        )

    @classmethod
    def rpt(cls, sigma: float, alpha: float, beta: float) -> "Noise":
        """Run-pause-tumble: ±sigma → 0 at rate alpha, 0 → ±sigma at rate
        beta/2 each."""
        n = cls._num
        return cls(f"rpt:sigma={n(sigma)},alpha={n(alpha)},beta={n(beta)}")

    @classmethod
    def states(cls, levels: "Sequence[float]", rates: "Sequence[Sequence[float]]") -> "Noise":
        """Any finite-state Markov noise: the levels and the generator (rates
        >= 0 off the diagonal, rows summing to 0)."""
        n = cls._num
        lv = ",".join(n(a) for a in levels)
        q = ",".join("[" + ",".join(n(x) for x in row) + "]" for row in rates)
        return cls(f"states:levels=[{lv}],rates=[{q}]")

    @classmethod
    def none(cls) -> "Noise":
        """No active noise (thermal noise alone: give ``temperature=``)."""
        return cls("none")

    @property
    def spec(self) -> str:
        return self._spec

    @property
    def kind(self) -> str:
        return self._spec.split(":", 1)[0]

    def __str__(self) -> str:
        return self._spec

    def __repr__(self) -> str:
        return f"Noise({self._spec!r})"

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Noise):
            return self._spec == other._spec
        if isinstance(other, str):
            return self._spec == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._spec)


class Drag:
    """A drag law g(v) of the equation of motion dv/dt = -g(v) + eta(t), Eq. (5).

    ``Drag("tan")`` (shear-thickening, Table 1), ``Drag("tanh")``
    (shear-thinning, needs Sigma < 1), ``Drag("linear")`` (Newtonian) and
    ``Drag("cubic")`` (g = v + v³/3), and the parameterised media
    ``Drag("power:n=0.5")`` (g = k sign(v)|v|^n, k = 1 by default) and
    ``Drag("carreau:n=0.5,a=1")`` (g = v [1 + (a v)²]^((n-1)/2)),
    ``Drag("coulomb:mu=0.5,gamma=1")`` (g = mu sign(v) + gamma v, needs
    Sigma > mu: below it the particle sticks at v = 0), and any odd,
    increasing law as an expression in v, ``Drag("expr:v + 0.3*v^3")``;
    the list
    comes from the Rust registry (:func:`drag_laws`), which also validates
    the parameters (a bad one is a ``ValueError`` naming it, from the
    function that runs). Accepted by every function as ``drag=`` and by
    :class:`Params`; a plain string works too.

    Attributes
    ----------
    name : str
        What ``--drag`` takes: the registry name, with ``:key=value,...``
        for a law with parameters.
    law : str
        The registry name alone (``power`` for ``power:n=0.5``).
    description : str
        One line, e.g. "shear-thickening, g = tan v".
    force_limit : float
        The largest admissible Sigma (exclusive); ``inf`` when unbounded.
    """

    __slots__ = ("_name",)

    def __init__(self, name: "str | Drag") -> None:
        if isinstance(name, Drag):
            name = name.name
        if not isinstance(name, str) or name.split(":", 1)[0] not in _laws():
            raise ValueError(
                f"unknown drag law {name!r} (known: {_known_laws()})"
            )
        self._name = name

    @property
    def name(self) -> str:
        return self._name

    @property
    def law(self) -> str:
        return self._name.split(":", 1)[0]

    @property
    def description(self) -> str:
        return str(_laws()[self.law]["description"])

    @property
    def force_limit(self) -> float:
        return float(_laws()[self.law]["force_limit"])

    def __str__(self) -> str:
        return self._name

    def __repr__(self) -> str:
        return f"Drag({self._name!r})"

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Drag):
            return self._name == other._name
        if isinstance(other, str):
            return self._name == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._name)


def drag_laws() -> List[Drag]:
    """Every registered drag law, in the CLI's order."""
    return [Drag(name) for name in _laws()]


def _number(name: str, value: Any) -> float:
    """A real number as float (bools refused: ``sigma=True`` is a typo)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, not {type(value).__name__}")
    return float(value)


class Reset:
    """Base class of reset rules: ``options()`` gives the CLI options it sets."""

    __slots__ = ()

    def options(self) -> Dict[str, float]:  # pragma: no cover - abstract
        raise NotImplementedError


class PoissonReset(Reset):
    """Poissonian velocity resetting, the paper's protocol (Eq. (3)).

    At rate ``rate`` (r) the velocity jumps to ``velocity`` (v_r); position
    and noise state are kept. Maps to the options ``rate`` and
    ``reset_velocity``. ``PoissonReset(0)`` is no resetting.
    """

    __slots__ = ("_rate", "_velocity")

    def __init__(self, rate: float, velocity: float = 0.0) -> None:
        self._rate = _number("rate", rate)
        self._velocity = _number("velocity", velocity)

    @property
    def rate(self) -> float:
        return self._rate

    @property
    def velocity(self) -> float:
        return self._velocity

    def options(self) -> Dict[str, float]:
        return {"rate": self._rate, "reset_velocity": self._velocity}

    def __repr__(self) -> str:
        return f"PoissonReset(rate={self._rate!r}, velocity={self._velocity!r})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PoissonReset):
            return NotImplemented
        return (self._rate, self._velocity) == (other._rate, other._velocity)

    def __hash__(self) -> int:
        return hash((PoissonReset, self._rate, self._velocity))


# Python attribute -> CLI option name of the model fields, in CLI order.
_FIELDS: Tuple[Tuple[str, str], ...] = (
    ("drag", "drag"),
    ("sigma", "sigma"),
    ("lambda_", "lambda"),
    ("noise", "noise"),
    ("temperature", "temperature"),
    ("rate", "rate"),
    ("reset_velocity", "reset_velocity"),
    ("reset_to", "reset_to"),
    ("reset_period", "reset_period"),
    ("reset_clock", "reset_clock"),
    ("reset_position", "reset_position"),
    ("refractory", "refractory"),
)


class Params:
    """A model parameter set: drag law, Sigma, lambda and the reset rule.

    Eq. (5) with telegraph noise ±Sigma flipping at rate lambda (Eq. (6))
    and resetting v -> v_r at rate r (Eq. (3)). Fields left out (``None``)
    take each command's own default (``analytic`` has rate 0, the others
    rate 2). Pass it to any function as ``params=``; a field also given as
    its own keyword raises ValueError.

    ``Params(drag="tanh", sigma=0.6, lambda_=0.85, reset=PoissonReset(1.0))``
    is the same as ``Params(drag="tanh", sigma=0.6, lambda_=0.85, rate=1.0,
    reset_velocity=0.0)``. ``lambda`` may be given as ``**{"lambda": x}``.
    """

    __slots__ = ("_values",)

    def __init__(
        self,
        drag: "str | Drag | None" = None,
        sigma: Optional[float] = None,
        lambda_: Optional[float] = None,
        reset: Optional[Reset] = None,
        *,
        rate: Optional[float] = None,
        reset_velocity: Optional[float] = None,
        reset_to: Optional[str] = None,
        reset_period: Optional[float] = None,
        reset_clock: Optional[str] = None,
        reset_position: Optional[float] = None,
        refractory: Optional[str] = None,
        noise: Optional[str] = None,
        temperature: Optional[float] = None,
        **kwargs: Any,
    ) -> None:
        if "lambda" in kwargs:
            if lambda_ is not None:
                raise ValueError("lambda_ given twice (as lambda_= and as lambda=)")
            lambda_ = kwargs.pop("lambda")
        if kwargs:
            bad = ", ".join(sorted(kwargs))
            raise ValueError(
                f"unknown keyword {bad} for irtp.Params "
                "(known: drag, sigma, lambda_, reset, rate, reset_velocity, reset_to, "
                "reset_period, reset_clock, reset_position, refractory, noise, temperature)"
            )
        if reset is not None:
            if not isinstance(reset, Reset):
                raise TypeError(f"reset must be a reset rule such as PoissonReset, not {reset!r}")
            for key, value in reset.options().items():
                if {"rate": rate, "reset_velocity": reset_velocity}[key] is not None:
                    raise ValueError(f"{key} given twice (by reset= and by {key}=)")
            rate, reset_velocity = reset.options()["rate"], reset.options()["reset_velocity"]
        values: Dict[str, Any] = {}
        if drag is not None:
            values["drag"] = Drag(drag)
        fields: Tuple[Tuple[str, Any], ...] = (
            ("sigma", sigma), ("lambda_", lambda_), ("rate", rate),
            ("reset_velocity", reset_velocity), ("reset_period", reset_period),
            ("reset_position", reset_position), ("temperature", temperature))
        for attr, given in fields:
            if given is not None:
                values[attr] = _number(attr, given)
        if reset_to is not None:
            values["reset_to"] = str(reset_to)
        if reset_clock is not None:
            values["reset_clock"] = str(reset_clock)
        if refractory is not None:
            values["refractory"] = str(refractory)
        if noise is not None:
            values["noise"] = str(noise)
        self._values = values

    @classmethod
    def from_mapping(cls, m: Mapping[str, Any]) -> "Params":
        """From a mapping with the keys of run.json's model (``drag``, ``sigma``,
        ``lambda``, ``rate``, ``reset_velocity``), e.g. ``result.summary["params"]``
        of :func:`fp_stationary` or ``result.params["model"]``. A protocol
        other than the paper's is recorded as the spec ``reset``
        (``point:v=0.2,noise=redrawn``), which becomes ``reset_to`` (and
        carries the reset velocity)."""
        d = dict(m)
        if "noise" in d:
            # A noise spec replaces sigma and lambda (files record neither).
            d.pop("sigma", None)
            d.pop("lambda", None)
        if isinstance(d.get("reset"), str):
            d["reset_to"] = d.pop("reset")
            d.pop("reset_velocity", None)
        return cls(**d)

    drag = property(lambda self: self._values.get("drag"), doc="Drag law (or None: default).")
    sigma = property(lambda self: self._values.get("sigma"), doc="Noise amplitude Sigma.")
    lambda_ = property(lambda self: self._values.get("lambda_"), doc="Flip rate lambda.")
    rate = property(lambda self: self._values.get("rate"), doc="Reset rate r.")
    reset_velocity = property(
        lambda self: self._values.get("reset_velocity"), doc="Reset velocity v_r."
    )
    reset_to = property(
        lambda self: self._values.get("reset_to"),
        doc="The resetting protocol as a spec (``gauss:mean=0,std=0.3``), or None.",
    )
    reset_period = property(
        lambda self: self._values.get("reset_period"),
        doc="Periodic resetting: the period T (then no rate), or None.",
    )
    reset_clock = property(
        lambda self: self._values.get("reset_clock"),
        doc="Renewal resetting: the waiting-time law (``gamma:k=2,theta=0.5``), or None.",
    )
    reset_position = property(
        lambda self: self._values.get("reset_position"),
        doc="Position resetting: x_r, or None (position kept).",
    )
    noise = property(
        lambda self: self._values.get("noise"),
        doc="The noise as a spec (``rpt:sigma=1,alpha=1,beta=2``; docs/equations.md, "
        "'Noise kinds'), or None: the paper's telegraph noise from sigma and lambda_.",
    )
    temperature = property(
        lambda self: self._values.get("temperature"),
        doc="Temperature T of the thermal noise, or None (0).",
    )
    refractory = property(
        lambda self: self._values.get("refractory"),
        doc="Refractory period after a reset (``exp:mean=0.5``, ``fixed:t=0.5``), or None.",
    )

    @property
    def reset(self) -> Optional[PoissonReset]:
        """The reset rule when the rate is set (velocity 0 unless given)."""
        if self.rate is None:
            return None
        return PoissonReset(self.rate, self.reset_velocity or 0.0)

    def options(self) -> Dict[str, Any]:
        """The fields that are set, under the CLI's option names (``lambda``)."""
        out: Dict[str, Any] = {}
        for attr, cli in _FIELDS:
            if attr in self._values:
                value = self._values[attr]
                if isinstance(value, Drag):
                    value = value.name
                elif isinstance(value, Noise):
                    value = value.spec
                out[cli] = value
        return out

    def replace(self, **changes: Any) -> "Params":
        """A copy with some fields changed (``None`` unsets a field)."""
        current: Dict[str, Any] = dict(self._values)
        if "lambda" in changes:
            changes["lambda_"] = changes.pop("lambda")
        if "reset" in changes:
            reset = changes.pop("reset")
            current.pop("rate", None)
            current.pop("reset_velocity", None)
            if reset is not None:
                current["rate"] = reset.options()["rate"]
                current["reset_velocity"] = reset.options()["reset_velocity"]
        current.update(changes)
        return Params(**{k: v for k, v in current.items() if v is not None})

    def __iter__(self) -> Iterator[Tuple[str, Any]]:
        return iter(self.options().items())

    def __repr__(self) -> str:
        inner = ", ".join(f"{attr}={self._values[attr]!r}" for attr, _ in _FIELDS
                          if attr in self._values)
        return f"Params({inner})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Params):
            return NotImplemented
        return self.options() == other.options()

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.options().items())))
