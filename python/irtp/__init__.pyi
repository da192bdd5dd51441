# Type stubs of the public API of irtp. The defaults live in the Rust CLI
# definitions (help(irtp.simulate) shows them); here they are written `...`.

import os
import pathlib
from typing import (
    Any,
    Callable,
    Dict,
    Iterator,
    List,
    Literal,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
    overload,
)

import numpy as np
import numpy.typing as npt

__version__: str
__git_revision__: Optional[str]

Array = npt.NDArray[np.float64]
PathLike = Union[str, "os.PathLike[str]"]
# Laws without parameters; a law with parameters is a spec string
# ("power:n=0.5", "carreau:n=0.5,a=1").
DragName = Literal["tan", "tanh", "linear", "cubic"]
ProgressArg = Union[bool, Callable[[str, int, int], None]]
ParamsArg = Union["Params", Mapping[str, Any], None]

class NumericalError(RuntimeError):
    """A numerical failure of a solver or sampler."""

class Drag:
    def __init__(self, name: Union[str, Drag]) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def law(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def force_limit(self) -> float: ...
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...

def drag_laws() -> List[Drag]: ...

class Noise:
    def __init__(self, spec: Union[str, Noise]) -> None: ...
    @classmethod
    def telegraph(
        cls,
        sigma: Optional[float] = None,
        lambda_: Optional[float] = None,
        *,
        plus: Optional[float] = None,
        minus: Optional[float] = None,
        rate_plus: Optional[float] = None,
        rate_minus: Optional[float] = None,
    ) -> Noise: ...
    @classmethod
    def rpt(cls, sigma: float, alpha: float, beta: float) -> Noise: ...
    @classmethod
    def states(cls, levels: Sequence[float], rates: Sequence[Sequence[float]]) -> Noise: ...
    @classmethod
    def none(cls) -> Noise: ...
    @property
    def spec(self) -> str: ...
    @property
    def kind(self) -> str: ...
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...

class Reset:
    def options(self) -> Dict[str, float]: ...

class PoissonReset(Reset):
    def __init__(self, rate: float, velocity: float = 0.0) -> None: ...
    @property
    def rate(self) -> float: ...
    @property
    def velocity(self) -> float: ...
    def options(self) -> Dict[str, float]: ...

class Params:
    def __init__(
        self,
        drag: Union[str, Drag, None] = None,
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
    ) -> None: ...
    @classmethod
    def from_mapping(cls, m: Mapping[str, Any]) -> Params: ...
    @property
    def drag(self) -> Optional[Drag]: ...
    @property
    def sigma(self) -> Optional[float]: ...
    @property
    def lambda_(self) -> Optional[float]: ...
    @property
    def rate(self) -> Optional[float]: ...
    @property
    def reset_velocity(self) -> Optional[float]: ...
    @property
    def reset_to(self) -> Optional[str]: ...
    @property
    def reset_period(self) -> Optional[float]: ...
    @property
    def reset_clock(self) -> Optional[str]: ...
    @property
    def reset_position(self) -> Optional[float]: ...
    @property
    def refractory(self) -> Optional[str]: ...
    @property
    def noise(self) -> Optional[str]: ...
    @property
    def temperature(self) -> Optional[float]: ...
    @property
    def reset(self) -> Optional[PoissonReset]: ...
    def options(self) -> Dict[str, Any]: ...
    def replace(self, **changes: Any) -> Params: ...
    def __iter__(self) -> Iterator[Tuple[str, Any]]: ...
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...

class Result:
    command: str
    method: str
    seed: Optional[int]
    summary: Any
    params: Dict[str, Any]
    provenance: Dict[str, Any]
    tables: Dict[str, Dict[str, Array]]
    text: str
    out: Optional[str]
    files: Optional[List[str]]
    def __getattr__(self, name: str) -> Any: ...
    def to_dict(self, lists: bool = False) -> Dict[str, Any]: ...
    def to_pandas(self, table: Optional[str] = None) -> Any: ...
    # An xarray.Dataset (xarray is optional: pip install './python[xarray]').
    def to_xarray(self) -> Any: ...
    # A matplotlib Axes (matplotlib is optional: pip install './python[plot]').
    def plot(self, panel: Optional[int] = None, ax: Any = None) -> Any: ...

class SimulateResult(Result):
    summary: Dict[str, Any]
    # moments
    t: Array
    v_mean: Array
    v_mean_err: Array
    v2: Array
    v2_err: Array
    x_mean: Array
    x_mean_err: Array
    x2: Array
    x2_err: Array
    # density
    v: Array
    p: Array
    p_err: Array
    p_final: Array
    p_final_err: Array
    # summary
    particles: int
    steps: Optional[int]  # Euler time steps summed over particles (None for "exact")
    events: Optional[int]  # exact sampler's events summed over particles (None for "euler")
    v2_final: float
    v2_final_err: float
    x2_final: float
    x2_final_err: float
    d_eff_msd: Optional[float]
    d_eff_msd_err: Optional[float]
    # point masses of the stationary law: [{"v", "mass", "err"}], not in p
    atoms: List[Dict[str, Any]]
    wall_time_s: float

class AnalyticResult(Result):
    summary: Dict[str, Any]
    v: Array
    p: Array
    cdf: Array
    regime: str
    regime_description: str
    v_lower: float
    v_upper: float
    v2: float
    v4: float
    edge_exponent: float

class FpStationaryResult(Result):
    summary: Dict[str, Any]
    v: Array
    p: Array
    p_plus: Array
    p_minus: Array
    dv: Array
    v2: float
    v_mean: float
    d_eff: float
    d_eff_err: Optional[float]
    # point masses of the stationary law: [{"v", "mass", "err"}], not in p
    atoms: List[Dict[str, Any]]
    cells: int
    mass: float

class FpMsdResult(Result):
    summary: Dict[str, Any]
    # moments
    t: Array
    mass: Array
    v_mean: Array
    v2: Array
    x_mean: Array
    xv: Array
    x2: Array
    alpha: Array

class FpTransientResult(Result):
    summary: Dict[str, Any]
    # moments (snapshots: tables["snapshots"])
    t: Array
    v2: Array
    v_mean: Array
    mass: Array
    v: Array
    p: Array
    p_plus: Array
    p_minus: Array
    v2_final: float
    v_mean_final: float
    mass_error_max: float
    dt: Optional[float]
    steps: int
    cells: int

class MfptResult(Result):
    summary: Dict[str, Any]
    # profile (method "backward" only; then tau is the column, summary["tau"] the value)
    v0: Array
    tau_plus: Any
    tau_minus: Any
    tau: Any
    tau_err: Optional[float]
    error_estimate: float
    particles: int
    censored: int
    # particles: censoring (tau is None when censored > 0) and table survival
    censored_fraction: float
    rmst: float
    rmst_err: float
    tau_lower_bound: Optional[float]
    t_max: float
    survival: Array
    survival_err: Array
    at_risk: Array

class MfptScanResult(Result):
    summary: List[Dict[str, Any]]
    vt: Array
    rate: Array
    x0: Array
    xt: Array
    tau: Array
    tau_plus: Array
    tau_minus: Array
    error_estimate: Array
    tau_sim: Array
    tau_sim_err: Array
    tau_plus_sim: Array
    tau_plus_sim_err: Array
    tau_minus_sim: Array
    tau_minus_sim_err: Array
    censored: Array
    censored_fraction: Array
    rmst_sim: Array
    rmst_sim_err: Array

class MfptOptimizeResult(Result):
    summary: Dict[str, Any]
    rate: Array
    tau: Array
    r_opt: float
    tau_opt: float
    tau_opt_err: float
    r_opt_range: List[Optional[float]]
    tau_plus_opt: float
    tau_minus_opt: float
    tau_r0: float
    dtau_dr_r0: float
    interior: bool
    at_upper_bound: bool
    r_min: float
    r_max: float

class MfptDistributionResult(Result):
    summary: Dict[str, Any]
    # backward: table distribution
    t: Array
    survival: Array
    density: Array
    survival_plus: Array
    density_plus: Array
    survival_minus: Array
    density_minus: Array
    # exact: tables histogram and survival
    t_lo: Array
    t_hi: Array
    density_err: Array
    count: Array
    survival_err: Array
    at_risk: Array
    tau: float
    second_moment: float
    variance: float
    cv: float

class ReproduceResult(Result):
    summary: Dict[str, Any]

def simulate(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    particles: int = ...,
    dt: Optional[float] = ...,
    t_max: float = ...,
    samples: int = ...,
    grid: Literal["linear", "log"] = ...,
    t_min: float = ...,
    burn_in: float = ...,
    bins: int = ...,
    method: Literal["exact", "euler"] = ...,
    events: Optional[Literal["geometric", "bernoulli"]] = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> SimulateResult: ...
def analytic(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    points: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    lambda_: float = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> AnalyticResult: ...
def fp_stationary(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    cells: int = ...,
    mesh: Literal["graded", "uniform"] = ...,
    no_extrapolate: bool = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> FpStationaryResult: ...
def fp_transient(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    t_max: float,
    scheme: Literal["trbdf2", "paper"] = ...,
    cells: int = ...,
    samples: int = ...,
    snapshots: int = ...,
    cfl: Optional[float] = ...,
    rtol: Optional[float] = ...,
    atol: Optional[float] = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> FpTransientResult: ...
def fp_msd(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    t_min: float = ...,
    t_max: float = ...,
    samples: int = ...,
    cells: int = ...,
    levels: int = ...,
    rtol: float = ...,
    mesh: Literal["graded", "uniform"] = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> FpMsdResult: ...
def mfpt(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    v0: float,
    cells: int = ...,
    vt: float = ...,
    xt: float = ...,
    interval: str = ...,
    x0: float = ...,
    cells_x: int = ...,
    cells_v: int = ...,
    time_steps: int = ...,
    horizon_tail: float = ...,
    method: Literal["backward", "exact", "euler", "ode", "renewal"] = ...,
    particles: int = ...,
    dt: float = ...,
    t_max: float = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> MfptResult: ...
def mfpt_scan(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    v0: float,
    cells: int = ...,
    vt: Optional[float] = ...,
    xt: float = ...,
    interval: str = ...,
    x0: float = ...,
    cells_x: int = ...,
    cells_v: int = ...,
    over: Literal["vt", "rate", "x0", "xt"],
    from_: float,
    to: float,
    points: int = ...,
    log: bool = ...,
    method: Literal["backward", "exact", "euler", "ode"] = ...,
    particles: int = ...,
    dt: float = ...,
    t_max: float = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> MfptScanResult: ...
def mfpt_optimize(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    v0: float,
    cells: int = ...,
    vt: float = ...,
    xt: float = ...,
    interval: str = ...,
    x0: float = ...,
    cells_x: int = ...,
    cells_v: int = ...,
    r_min: float = ...,
    r_max: float = ...,
    grid_points: int = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> MfptOptimizeResult: ...
def mfpt_distribution(
    *,
    drag: Union[DragName, str, Drag] = ...,
    sigma: float = ...,
    lambda_: float = ...,
    noise: str = ...,
    temperature: float = ...,
    rate: float = ...,
    reset_velocity: float = ...,
    reset_noise: Literal["kept", "redrawn"] = ...,
    reset_to: str = ...,
    reset_period: float = ...,
    reset_clock: str = ...,
    reset_position: float = ...,
    refractory: str = ...,
    v0: float,
    cells: int = ...,
    vt: float = ...,
    xt: float = ...,
    interval: str = ...,
    x0: float = ...,
    method: Literal["backward", "exact"] = ...,
    t_max: float = ...,
    points: int = ...,
    grid: Literal["linear", "log"] = ...,
    t_min: float = ...,
    rtol: float = ...,
    particles: int = ...,
    cells_x: int = ...,
    cells_v: int = ...,
    seed: int = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    max_work: float = ...,
    max_memory: float = ...,
    params: ParamsArg = ...,
    reset: Optional[Reset] = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> MfptDistributionResult: ...
def reproduce(
    *figures: Literal["fig1", "fig2", "fig3", "fig5", "fig6", "fig7", "fpt", "media", "search", "all"],
    out: PathLike,
    force: bool = ...,
    quick: bool = ...,
    seed: int = ...,
    progress: ProgressArg = ...,
    threads: Optional[int] = ...,
) -> ReproduceResult: ...

# Reading what the CLI (or ``out=``) wrote; xarray.Dataset results are Any
# (xarray is an optional dependency).
def load(path: PathLike) -> Result: ...
def load_sweep(path: PathLike) -> Any: ...
# A heat map of a load_sweep Dataset over its first two axes: a matplotlib Axes.
def plot_sweep(ds: Any, var: Optional[str] = None, ax: Any = None) -> Any: ...
def collect(
    path: PathLike,
    out: PathLike,
    format: Literal["netcdf", "zarr", "csv"] = ...,
    engine: Optional[Literal["h5netcdf", "netcdf4"]] = ...,
) -> pathlib.Path: ...
