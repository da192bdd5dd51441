"""The paper's Euler loop (Eqs. 14-16) in numba, for a speed comparison with
`irtp simulate`.

Same algorithm and the same work per step as the Rust kernel: per step,
observe (record x, v at grid steps; in the window [burn_in, t_max] add v, v^2
and the occupation of v's histogram bin), x += v dt with the old v, then with
probability r dt reset v to v_r else v += dt (eta - tan v), then flip eta with
probability q = (1 - exp(-2 lambda dt))/2 -- two uniform draws per step, as in
the paper. Particles start at x = v = 0, eta = +-Sigma with probability 1/2.

Functions: simulate(..., parallel) -> dict of summary numbers. The serial
variant is a plain loop; the parallel one uses numba.prange over particles
(per-particle rows for the histogram and recorded moments, reduced after).
"""
import math
import time

import numpy as np
from numba import njit, prange


@njit(inline="always")
def _particle(i, n_steps, dt, sigma, p_reset, q_flip, vr, n_burn, rec_steps,
              v_lo, scale, bins, hist_row, rec_v, rec_x):
    v = 0.0
    x = 0.0
    eta = sigma if np.random.random() < 0.5 else -sigma
    k = 0
    next_rec = rec_steps[0]
    sv = 0.0
    sv2 = 0.0
    for n in range(n_steps):
        if n == next_rec:
            rec_v[i, k] = v
            rec_x[i, k] = x
            k += 1
            next_rec = rec_steps[k] if k < rec_steps.shape[0] else -1
        if n >= n_burn:
            sv += v
            sv2 += v * v
            b = int((v - v_lo) * scale)
            if b < 0:
                b = 0
            elif b >= bins:
                b = bins - 1
            hist_row[b] += 1.0
        x += v * dt
        if np.random.random() < p_reset:
            v = vr
        else:
            v += dt * (eta - math.tan(v))
        if np.random.random() < q_flip:
            eta = -eta
    if k < rec_steps.shape[0]:
        rec_v[i, k] = v
        rec_x[i, k] = x
    w = n_steps - n_burn
    return sv / w, sv2 / w


@njit(cache=True)
def run_serial(particles, n_steps, dt, sigma, lam, r, vr, n_burn, rec_steps,
               bins, seed):
    np.random.seed(seed)
    p_reset = r * dt
    q_flip = 0.5 * (1.0 - math.exp(-2.0 * lam * dt))
    v_hi = math.atan(sigma)
    v_lo = -v_hi
    scale = bins / (v_hi - v_lo)
    hist = np.zeros((1, bins))
    rec_v = np.zeros((particles, rec_steps.shape[0]))
    rec_x = np.zeros((particles, rec_steps.shape[0]))
    v2avg = np.zeros(particles)
    for i in range(particles):
        _, v2avg[i] = _particle(i, n_steps, dt, sigma, p_reset, q_flip, vr,
                                n_burn, rec_steps, v_lo, scale, bins, hist[0],
                                rec_v, rec_x)
    return v2avg, rec_v, rec_x, hist


@njit(cache=True, parallel=True)
def run_parallel(particles, n_steps, dt, sigma, lam, r, vr, n_burn, rec_steps,
                 bins, seed):
    np.random.seed(seed)  # numba: seeds the calling thread's generator only
    p_reset = r * dt
    q_flip = 0.5 * (1.0 - math.exp(-2.0 * lam * dt))
    v_hi = math.atan(sigma)
    v_lo = -v_hi
    scale = bins / (v_hi - v_lo)
    hist = np.zeros((particles, bins))
    rec_v = np.zeros((particles, rec_steps.shape[0]))
    rec_x = np.zeros((particles, rec_steps.shape[0]))
    v2avg = np.zeros(particles)
    for i in prange(particles):
        _, v2avg[i] = _particle(i, n_steps, dt, sigma, p_reset, q_flip, vr,
                                n_burn, rec_steps, v_lo, scale, bins, hist[i],
                                rec_v, rec_x)
    return v2avg, rec_v, rec_x, hist


def simulate(particles=4000, t_max=20.0, dt=1e-3, sigma=3.0, lam=0.5, r=2.0,
             vr=0.0, burn_in=10.0, samples=201, bins=100, seed=1,
             parallel=False):
    n_steps = int(round(t_max / dt))
    n_burn = int(round(burn_in / dt))
    rec_steps = np.round(np.linspace(0.0, t_max, samples) / dt).astype(np.int64)
    f = run_parallel if parallel else run_serial
    t0, c0 = time.perf_counter(), time.process_time()
    v2avg, rec_v, rec_x, hist = f(particles, n_steps, dt, sigma, lam, r, vr,
                                  n_burn, rec_steps, bins, seed)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    steps = particles * n_steps
    return {
        "v2": float(v2avg.mean()),
        "v2_err": float(v2avg.std(ddof=1) / math.sqrt(particles)),
        "x2_final": float((rec_x[:, -1] ** 2).mean()),
        "x2_final_err": float((rec_x[:, -1] ** 2).std(ddof=1) / math.sqrt(particles)),
        "particles": particles,
        "steps": steps,
        "wall_time_s": wall,
        "cpu_time_s": cpu,
        "particle_steps_per_s": steps / wall,
        "particle_steps_per_cpu_s": steps / cpu,
    }


if __name__ == "__main__":
    import json
    import sys
    par = "--parallel" in sys.argv
    simulate(particles=8, t_max=0.1, burn_in=0.05, parallel=par)  # JIT warm-up
    print(json.dumps(simulate(parallel=par)))
