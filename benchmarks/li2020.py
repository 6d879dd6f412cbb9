"""Li2020 closed loop: JAX engine vs a plain numpy reference implementation (same model, RK4, dt).

The numpy reference is written independently of the JAX code: the paper's Sec. IV functions (faults,
disturbances, delays) are hard-coded numpy lambdas, the history is a Python list of per-step samples
with linear interpolation and constant prehistory, and the loop is a plain Python RK4 loop. It is used

* as the "numpy reference" of the performance issue (wall time per step), and
* by ``tests/papers/li2020/test_closed_loop.py`` as an independent implementation of the same closed
  loop (the two must agree to round-off over a few hundred steps).

Run: ``python benchmarks/li2020.py [--steps 2000] [--full]``. Prints the wall time per step for JAX and
numpy and the wall time of a full ``li2020-thm2-delays`` run (3000 s at dt = 0.01 s) after compilation.
Timing is noisy on shared machines: medians of repeats are reported.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

__all__ = ["NumpyLi2020", "numpy_reference_step_time", "jax_closed_loop", "jax_full_run_time"]

MU = 3.986004418e14  # m^3/s^2


def _paper_functions():
    """The paper's Sec. IV time functions (numpy; E000-06 (t-20) onset for alpha_i3)."""
    i = np.arange(1, 5, dtype=float)

    def gamma(t):
        a1 = np.where(t >= 10, 1 - 0.1 * (i + 1) * np.exp(-(t - 10)), 1.0)
        a2 = np.where(t >= 15, 1 - 0.1 * np.exp(-0.5 * i * (t - 15)), 1.0)
        a3 = np.where(t >= 20, 1 - 0.05 * (i + 2) * np.exp(-0.2 * (t - 20)), 1.0)
        return np.stack([a1, a2, a3], axis=-1)

    def delta(t):
        return 0.1 * np.stack(
            [
                (i + 1) * np.cos(0.1 * t) + 2 * np.exp(-0.2 * t),
                i * np.sin(0.2 * t) + np.exp(-0.3 * t),
                (2 * i - 1) * np.cos(0.3 * t) - np.exp(-0.4 * t),
            ],
            axis=-1,
        )

    def h(t):
        return 0.05 * np.stack(
            [
                (i + 1) * np.cos(0.1 * t) + 2 * i * np.sin(0.2 * t),
                2 * i * np.cos(0.2 * t) + 3 * i,
                (i - 3) * np.sin(0.1 * t) - 2 * i,
            ],
            axis=-1,
        )

    delays = {
        (0, 2): lambda t: 1 - 0.2 * math.cos(0.4 * t),
        (1, 0): lambda t: 1 + 0.2 * math.sin(0.2 * t),
        (2, 1): lambda t: 2 + 0.4 * math.sin(0.2 * t),
        (2, 3): lambda t: 3 + 0.6 * math.sin(0.2 * t),
        (3, 0): lambda t: 1 + 0.2 * math.cos(0.2 * t),
    }
    return gamma, delta, h, delays


class NumpyLi2020:
    """Plain numpy closed loop of Li2020 with the paper's data (law 'thm1', 'thm2' or 'sir-ftc')."""

    def __init__(self, law: str = "thm2", dt: float = 0.01, d_sign: float = 1.0):
        self.law, self.dt, self.d_sign = law, dt, d_sign
        self.mass = np.array([100.0, 120.0, 115.0, 108.0])
        a, e = 7000e3, 0.02
        self.p, self.e = a * (1 - e**2), e
        self.C = np.array([[0, 0, 0.5, 0], [0.6, 0, 0, 0], [0, 0.5, 0, 0.4], [0.6, 0, 0, 0]], float)
        ph = np.array([0, np.pi / 2, np.pi, 3 * np.pi / 2])
        self.rho_bar = 500 * np.stack(
            [0.5 * np.cos(ph), -np.sin(ph), np.sqrt(3) / 2 * np.cos(ph)], -1
        )
        Tc = 2 * np.pi / np.sqrt(MU / a**3)
        self.chi = -0.25 * Tc**2 / (2 * np.log(1e-6))
        self.k, self.lam = 0.2, (20.0 if law == "thm1" else 15.0)
        self.gamma_a, self.eta, self.mu_a, self.ups = 0.1, 1.0, 1.0, 0.01
        self.gamma, self.delta, self.h, self.delays = _paper_functions()
        rho0 = np.array(
            [[250, 20, 423], [-15, -505, 10], [-238, -10, -250 * np.sqrt(3)], [5, 500, 15]], float
        )
        # state vector: theta, rho (12), v (12), then m_hat, beta_hat, d_hat (4 each) or b_hat (4)
        adapt = [100.0] * 4 + [1.0] * 4 + [0.001] * 4 if law != "sir-ftc" else [10.0] * 4
        self.x = np.concatenate([[0.0], rho0.ravel(), np.zeros(12), adapt])
        self.k_step = 0
        self.hist = [self._s(0.0, self.x)]  # s(t_k) for k = 0, 1, ...

    def _desired(self, t):
        ex = np.exp(-t * t / (2 * self.chi))
        g, gd, gdd = 1 - ex, t / self.chi * ex, (1 / self.chi - t * t / self.chi**2) * ex
        ph, phd, phdd = np.pi / 6 * g, np.pi / 6 * gd, np.pi / 6 * gdd
        la, lad, ladd = 1 + 0.6 * g, 0.6 * gd, 0.6 * gdd
        c, s = np.cos(ph), np.sin(ph)
        R = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
        R1 = np.array([[-s, 0, -c], [0, 0, 0], [c, 0, -s]])
        R2 = np.array([[-c, 0, s], [0, 0, 0], [-s, 0, -c]])
        Rd, Rdd = phd * R1, phdd * R1 + phd**2 * R2
        cen = np.array([300.0, 0, 0])
        rd = la * self.rho_bar @ R.T + g * cen
        vd = self.rho_bar @ (lad * R + la * Rd).T + gd * cen
        ad = self.rho_bar @ (ladd * R + 2 * lad * Rd + la * Rdd).T + gdd * cen
        return rd, vd, ad

    def _s(self, t, x):
        rd, vd, _ = self._desired(t)
        rho, v = x[1:13].reshape(4, 3), x[13:25].reshape(4, 3)
        return (v - vd) + self.k * (rho - rd)

    def _delayed(self, j, tau):
        """s_j(tau) by linear interpolation of the per-step history; s_j(0) for tau < 0."""
        if tau <= 0:
            return self.hist[0][j]
        q = tau / self.dt
        lo = int(math.floor(q))
        w = q - lo
        hi = min(lo + 1, len(self.hist) - 1)
        return (1 - w) * self.hist[lo][j] + w * self.hist[hi][j]

    def rhs(self, t, x, t_fault):
        th = x[0]
        rho, v = x[1:13].reshape(4, 3), x[13:25].reshape(4, 3)
        one = 1 + self.e * np.cos(th)
        rc = self.p / one
        thd = np.sqrt(MU / self.p**3) * one**2
        thdd = -2 * MU / self.p**3 * self.e * np.sin(th) * one**3
        ri = np.sqrt((rc + rho[:, 0]) ** 2 + rho[:, 1] ** 2 + rho[:, 2] ** 2)
        g = MU / ri**3
        acc = np.stack(
            [
                2 * thd * v[:, 1]
                + thd**2 * rho[:, 0]
                + thdd * rho[:, 1]
                - g * rho[:, 0]
                - MU * rc / ri**3
                + MU / rc**2,
                -2 * thd * v[:, 0] - thdd * rho[:, 0] + thd**2 * rho[:, 1] - g * rho[:, 1],
                -g * rho[:, 2],
            ],
            -1,
        )
        rd, vd, ad = self._desired(t)
        s = (v - vd) + self.k * (rho - rd)
        Y = acc + self.k * (v - vd) - ad
        sig = np.exp(-0.001 * t)
        dx = np.zeros_like(x)
        if self.law == "sir-ftc":
            b = x[25:29]
            eps = 1.0 / 2.0
            ns = np.linalg.norm(s, axis=1)
            f = -(20.0 + b * 1.0 / (ns + eps))[:, None] * s
            dx[25:29] = -b + 10.0 * ns**2 / (ns + eps)
        else:
            mh, bh, dh = x[25:29], x[29:33], x[33:37]
            cons = np.zeros((4, 3))
            for i in range(4):
                for j in range(4):
                    if self.C[i, j] > 0:
                        if self.law == "thm1":
                            sj = s[j]
                        else:
                            sj = self._delayed(j, t - self.delays[(i, j)](t))
                        cons[i] += self.C[i, j] * (s[i] - sj)
            xi = (
                mh[:, None] * Y + self.lam * s + cons + self.d_sign * dh[:, None] * np.tanh(s / sig)
            )
            w = np.sum(xi * s, axis=1)
            f = -(bh**2 * w / np.sqrt(bh**2 * w**2 + sig**2))[:, None] * xi
            dx[25:29] = self.eta * np.sum(s * Y, axis=1)
            dx[29:33] = self.gamma_a * w
            dx[33:37] = -self.mu_a * self.ups * sig * dh + self.mu_a * np.sum(np.abs(s), axis=1)
        F = self.gamma(t_fault) * f + self.delta(t_fault)
        dx[0] = thd
        dx[1:13] = v.ravel()
        dx[13:25] = (acc + (self.h(t_fault) + F) / self.mass[:, None]).ravel()
        return dx

    def step(self):
        dt, k = self.dt, self.k_step
        t = k * dt
        tl = t + dt * (1 - 1e-9)  # left limit for faults at the last stage (as the JAX model)
        x = self.x
        k1 = self.rhs(t, x, t)
        k2 = self.rhs(t + dt / 2, x + dt / 2 * k1, t + dt / 2)
        k3 = self.rhs(t + dt / 2, x + dt / 2 * k2, t + dt / 2)
        k4 = self.rhs(t + dt, x + dt * k3, min(t + dt, tl))
        self.x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        self.k_step += 1
        self.hist.append(self._s(self.k_step * dt, self.x))

    def run(self, n_steps: int) -> np.ndarray:
        for _ in range(n_steps):
            self.step()
        return self.x

    # views
    @property
    def rho(self):
        return self.x[1:13].reshape(4, 3)

    @property
    def v(self):
        return self.x[13:25].reshape(4, 3)


def numpy_reference_step_time(n_steps: int = 1000, law: str = "thm2", repeats: int = 3) -> float:
    """Median wall time per step [s] of the numpy reference closed loop (thm2 with delays by default)."""
    times = []
    for _ in range(repeats):
        ref = NumpyLi2020(law)
        t0 = time.perf_counter()
        ref.run(n_steps)
        times.append((time.perf_counter() - t0) / n_steps)
    return statistics.median(times)


def jax_closed_loop(
    scenario: str = "li2020-thm2-delays",
    horizon: float | None = None,
    overrides: dict | None = None,
    check_finite: bool = True,
):
    """(jitted run, params, n_steps) of the JAX closed loop of a built-in li2020 scenario.

    ``jax.block_until_ready(run(params))`` runs it; the first call compiles. ``check_finite=False``
    runs the same step without the engine's divergence check (to measure its cost only; the method
    itself always checks).
    """
    import functools

    import jax

    from formation_ftc.api import load_scenario as load_li2020
    from formation_ftc.methods.composed import build
    from formation_ftc.sim import loop as loop_module

    ov = dict(overrides or {})
    if horizon is not None:
        ov["simulation.horizon"] = horizon
    scn = load_li2020(scenario, ov)
    compiled = build(scn)
    n = scn.simulation.n_steps
    if check_finite:
        return jax.jit(type(compiled).run), compiled, n
    engine_run = loop_module.run_fixed_step

    def run(p):  # traced once, at the first call: the loop's run with the check switched off
        loop_module.run_fixed_step = functools.partial(engine_run, check_finite=False)
        try:
            return p.run()
        finally:
            loop_module.run_fixed_step = engine_run

    return jax.jit(run), compiled, n


def jax_full_run_time(
    scenario: str = "li2020-thm2-delays",
    horizon: float | None = None,
    repeats: int = 3,
    check_finite: bool = True,
) -> tuple[float, float, int]:
    """(compile + first run [s], median wall time of a compiled run [s], n_steps)."""
    import jax

    run, params, n = jax_closed_loop(scenario, horizon, check_finite=check_finite)
    t0 = time.perf_counter()
    jax.block_until_ready(run(params))
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(run(params))
        times.append(time.perf_counter() - t0)
    return first, statistics.median(times), n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1000, help="numpy reference steps to time")
    ap.add_argument(
        "--horizon", type=float, default=None, help="JAX run horizon [s] (default: scenario's)"
    )
    ap.add_argument(
        "--single-thread",
        action="store_true",
        help="XLA:CPU with one intra-op thread (faster for single runs, PERFORMANCE.md)",
    )
    args = ap.parse_args()
    if args.single_thread:
        import os

        os.environ["XLA_FLAGS"] = (
            os.environ.get("XLA_FLAGS", "")
            + " --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
        )
    import formation_ftc  # noqa: F401  (x64)

    np_step = numpy_reference_step_time(args.steps)
    first, run_t, n = jax_full_run_time("li2020-thm2-delays", args.horizon)
    jax_step = run_t / n
    print(
        f"numpy reference (thm2, delays): {np_step * 1e6:8.1f} us/step -> {np_step * n:8.1f} s for {n} steps"
    )
    print(
        f"JAX li2020-thm2-delays        : {jax_step * 1e6:8.2f} us/step -> {run_t:8.3f} s for {n} steps "
        f"(compile + first run {first:.1f} s)"
    )
    print(f"speed-up JAX / numpy           : {np_step / jax_step:8.1f}x")
    _, run_nc, _ = jax_full_run_time("li2020-thm2-delays", args.horizon, check_finite=False)
    print(
        f"  same without the engine's finite check: {run_nc / n * 1e6:8.2f} us/step -> "
        f"{run_nc:8.3f} s"
    )
    for name in ("li2020-thm1", "li2020-sirftc"):
        f1, r1, n1 = jax_full_run_time(name, args.horizon)
        print(
            f"JAX {name:<27}: {r1 / n1 * 1e6:8.2f} us/step -> {r1:8.3f} s (compile + first {f1:.1f} s)"
        )


if __name__ == "__main__":
    main()
