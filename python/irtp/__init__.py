"""irtp: the inertial run-and-tumble particle with velocity resetting.

Python interface of the Rust library and CLI ``irtp`` for the model of
Howlader, Mondal & Das, "Velocity resetting of inertial run-and-tumble
particles in non-Newtonian media": dv/dt = -g(v) + eta(t) (Eq. (5)), telegraph
noise ±Sigma flipping at rate lambda (Eq. (6)), velocity reset to v_r at rate r
(Eq. (3)).

One function per CLI command, keywords named as the flags (``lambda_`` and
``from_`` for the Python keywords), the same numbers bit for bit:

- :func:`simulate`: particles (exact sampler or Euler, Eqs. (30)-(32))
- :func:`analytic`: the r = 0 density, Eqs. (34)-(35)
- :func:`fp_stationary`, :func:`fp_transient`: Fokker-Planck, Eqs. (11)-(12)
- :func:`mfpt`, :func:`mfpt_scan`, :func:`mfpt_optimize`,
  :func:`mfpt_distribution`: first passage,
  Eqs. (26)-(28)
- :func:`reproduce`: the paper's figures

Model pieces: :class:`Drag`, :class:`PoissonReset`, :class:`Params`.
Results: :class:`Result` (numpy columns as attributes, ``summary``,
``params``, ``provenance``, ``to_dict()``, ``to_pandas()``,
``to_xarray()``, ``plot()``). :func:`load` opens a run's ``--out`` directory as its
Result; :func:`load_sweep` stacks a sweep into one xarray Dataset and
:func:`collect` writes it as netCDF, zarr or CSV; :func:`plot_sweep` draws a
heat map of it. Numerical failures raise
:class:`NumericalError` (a RuntimeError).
"""

from . import _irtp
from ._api import (
    analytic,
    fp_stationary,
    fp_msd,
    fp_transient,
    mfpt,
    mfpt_distribution,
    mfpt_optimize,
    mfpt_scan,
    reproduce,
    simulate,
)
from ._irtp import NumericalError
from ._load import load
from ._plot import plot_sweep
from ._sweep import collect, load_sweep
from ._model import Drag, Noise, Params, PoissonReset, Reset, drag_laws
from ._results import (
    AnalyticResult,
    FpStationaryResult,
    FpMsdResult,
    FpTransientResult,
    MfptDistributionResult,
    MfptOptimizeResult,
    MfptResult,
    MfptScanResult,
    ReproduceResult,
    Result,
    SimulateResult,
)

__version__: str = _irtp.__version__
#: The git revision the extension was built from (None outside a checkout):
#: with ``__version__``, what every provenance record names.
__git_revision__: "str | None" = _irtp.__git_revision__

for _cls in (Drag, Reset, PoissonReset, Params, Result, SimulateResult, AnalyticResult,
             FpStationaryResult, FpTransientResult, FpMsdResult, MfptResult, MfptScanResult,
             MfptOptimizeResult, MfptDistributionResult, ReproduceResult):
    _cls.__module__ = "irtp"
del _cls

__all__ = [
    "simulate",
    "analytic",
    "fp_stationary",
    "fp_transient",
    "fp_msd",
    "mfpt",
    "mfpt_scan",
    "mfpt_optimize",
    "mfpt_distribution",
    "reproduce",
    "load",
    "load_sweep",
    "collect",
    "plot_sweep",
    "Drag",
    "Noise",
    "Reset",
    "PoissonReset",
    "Params",
    "drag_laws",
    "NumericalError",
    "Result",
    "SimulateResult",
    "AnalyticResult",
    "FpStationaryResult",
    "FpTransientResult",
    "FpMsdResult",
    "MfptResult",
    "MfptScanResult",
    "MfptOptimizeResult",
    "MfptDistributionResult",
    "ReproduceResult",
    "__version__",
    "__git_revision__",
]
