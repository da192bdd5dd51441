"""Side-by-side speed of the Euler simulation: numba (bench/numba_euler.py)
vs the Rust `irtp simulate` binary, same parameters and particle count.

Usage (from the repository root):
    cargo build --release && python3 bench/compare.py [--particles N] [--repeats R]

Parameters: tan drag, Sigma = 3, lambda = 0.5, r = 2, v_r = 0, dt = 1e-3,
t_max = 20, burn-in 10, 201 recording times, 100 bins (the CLI defaults).
Timing: numba is timed around the jitted call only, after a warm-up call,
so compilation is excluded; Rust reports its simulation wall time (from
--json), excluding process start and file output (no --out). Each
configuration is run R times, interleaved, and the median is reported.
Two rates: per wall-clock second, and per CPU second (numba: process_time
around the call; Rust: rusage of the whole child process). On a shared,
oversubscribed machine the CPU-second rate of the 1-thread runs is the
fairer measure of the kernels; the 2-thread wall rate shows the scaling
only when the machine is otherwise idle.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BIN = os.path.join(ROOT, "target", "release", "irtp")


def numba_run(particles, threads):
    code = (
        "import json, sys; sys.path.insert(0, %r); import numba_euler as m; "
        "m.simulate(particles=8, t_max=0.1, burn_in=0.05, parallel=%r); "
        "print(json.dumps(m.simulate(particles=%d, parallel=%r)))"
        % (HERE, threads > 1, particles, threads > 1)
    )
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads))
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def rust_run(particles, threads, events):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    cmd = [BIN, "simulate", "--method", "euler", "--dt", "1e-3",
           "--particles", str(particles), "--events", events, "--json"]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed: {proc.stderr.strip()}")
    out = proc.stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    r = json.loads(out)
    # `--json` prints the summary object; the simulation's record is under "results".
    r = r.get("results", r)
    # CPU seconds of the whole process (start-up and the summary included).
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    r["particle_steps_per_cpu_s"] = r["steps"] / cpu
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--particles", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--bin", default=None, help="the irtp binary (default: target/release/irtp)")
    a = ap.parse_args()
    global BIN
    BIN = a.bin or BIN
    configs = []
    for threads in (1, 2):
        configs.append(("numba (bernoulli)", threads,
                        lambda t=threads: numba_run(a.particles, t)))
        for ev in ("bernoulli", "geometric"):
            configs.append((f"rust ({ev})", threads,
                            lambda t=threads, e=ev: rust_run(a.particles, t, e)))
    rates = {(n, t): [] for n, t, _ in configs}
    cpu_rates = {(n, t): [] for n, t, _ in configs}
    v2 = {}
    for _ in range(a.repeats):
        for name, threads, f in configs:
            r = f()
            rates[(name, threads)].append(r["particle_steps_per_s"])
            cpu_rates[(name, threads)].append(r["particle_steps_per_cpu_s"])
            v2[(name, threads)] = (r["v2"], r["v2_err"])
    print(f"Euler, tan Sigma=3 lambda=0.5 r=2 dt=1e-3 t_max=20, "
          f"{a.particles} particles, median of {a.repeats}")
    print(f"{'implementation':<20}{'threads':>8}{'Msteps/wall-s':>15}"
          f"{'Msteps/cpu-s':>14}{'Msteps/wall-s each':>26}{'<v^2>':>22}")
    for name, threads, _ in configs:
        rs = rates[(name, threads)]
        cs = cpu_rates[(name, threads)]
        m, e = v2[(name, threads)]
        runs = " ".join(f"{x / 1e6:.1f}" for x in rs)
        print(f"{name:<20}{threads:>8}{statistics.median(rs) / 1e6:>15.1f}"
              f"{statistics.median(cs) / 1e6:>14.1f}{runs:>26}{m:>14.5f}±{e:.5f}")
    for threads in (1, 2):
        for label, table in (("wall", rates), ("cpu", cpu_rates)):
            base = statistics.median(table[("numba (bernoulli)", threads)])
            for ev in ("bernoulli", "geometric"):
                r = statistics.median(table[(f"rust ({ev})", threads)])
                print(f"ratio rust ({ev}) / numba, {threads} thread(s), "
                      f"per {label} second: {r / base:.2f}x")


if __name__ == "__main__":
    main()
