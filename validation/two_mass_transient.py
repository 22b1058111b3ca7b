#!/usr/bin/env python3
"""Reference solutions of vibrofem's lumped two-mass model (docs/spec/paper.md §5-§8, §19; docs/spec/scenes.md S8).

Writes
  reference/two_mass_transient.json  start-up from rest under P(t) = P_em |sin wt| (the paper's
                                     Mathcad normal form), x1 and x2 every 0.25 ms over 0-0.5 s,
                                     by scipy solve_ivp DOP853 at rtol 1e-12, integrated piecewise
                                     between the kinks of |sin wt| (t = k*pi/w = k*10 ms).
  reference/two_mass_steady.json     complex steady amplitudes X1, X2 (eq. (2) solved with
                                     numpy.linalg.solve) at a few frequencies for both k-term
                                     variants, and the undamped natural frequencies from
                                     scipy.linalg.eigh(K, M).

The Rust test `tests/app/dynamics.rs` compares against both files. Usage:
  validation/.venv/bin/python validation/two_mass_transient.py [--check]
--check recomputes and compares with the committed files instead of overwriting them
(exit code 1 on a difference beyond 1e-9 relative).
"""
import json
import sys
from math import pi
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

HERE = Path(__file__).resolve().parent
REF = HERE / "reference"

# The paper's machine (docs/spec/scenes.md S8).
P = dict(m1=206.7, m2=161.8, c12=3.808e7, c13=8 * 60266.0, mu1=2400.0, mu12=1830.0, mu13=230.0)
P_EM = 8 * 370.0            # total peak pull of 8 magnets, N
W_MAINS = 2 * pi * 50.0     # mains angular frequency, rad/s; force period 10 ms
T_END = 0.5                 # s
DT_OUT = 2.5e-4             # s (every 10th sample of the Rust default grid of 400 per 10 ms period)
RTOL, ATOL = 1e-12, np.array([1e-19, 1e-16, 1e-19, 1e-16])   # m, m/s, m, m/s


def rhs(t, X):
    """The paper's Mathcad normal form (§19): X = (x1, x1', x2, x2')."""
    m1, m2, c12, c13 = P["m1"], P["m2"], P["c12"], P["c13"]
    mu1, mu12, mu13 = P["mu1"], P["mu12"], P["mu13"]
    F = abs(P_EM * np.sin(W_MAINS * t))
    return [X[1],
            (-F - mu12 * (X[1] - X[3]) - c12 * (X[0] - X[2]) - mu1 * X[1]) / m1,
            X[3],
            (F - mu12 * (X[3] - X[1]) - c12 * (X[2] - X[0]) - c13 * X[2] - mu13 * X[3]) / m2]


def transient(method="DOP853", rtol=RTOL, atol=ATOL):
    n_out = int(round(T_END / DT_OUT))
    t_out = np.arange(n_out + 1) * DT_OUT
    kinks = np.arange(1, int(round(T_END * W_MAINS / pi)) + 1) * pi / W_MAINS
    edges = np.concatenate([[0.0], kinks[kinks < T_END - 1e-12], [T_END]])
    y = np.zeros(4)
    out = np.full((n_out + 1, 4), np.nan)
    out[0] = y
    nfev = 0
    for a, b in zip(edges[:-1], edges[1:]):
        sel = np.nonzero((t_out > a) & (t_out <= b + 1e-15))[0]
        s = solve_ivp(rhs, (a, b), y, method=method, rtol=rtol, atol=atol, dense_output=True)
        assert s.success, s.message
        nfev += s.nfev
        if len(sel):
            out[sel] = s.sol(np.minimum(t_out[sel], b)).T
        y = s.y[:, -1]
    assert not np.isnan(out).any()
    return t_out, out, nfev


def k_terms(om, variant):
    m1, m2, c12, c13 = P["m1"], P["m2"], P["c12"], P["c13"]
    mu1, mu12, mu13 = P["mu1"], P["mu12"], P["mu13"]
    if variant == "eq1":
        k11 = c12 - m1 * om**2 + 1j * (mu1 + mu12) * om
        k22 = c12 + c13 - m2 * om**2 + 1j * (mu12 + mu13) * om
    else:
        k11 = c12 + c13 - m1 * om**2 + 1j * (mu1 + mu13 + mu12) * om
        k22 = c12 - m2 * om**2 + 1j * mu12 * om
    k12 = -c12 - 1j * mu12 * om
    return np.array([[k11, k12], [k12, k22]])


def steady():
    F = 4 / (3 * pi) * P_EM
    freqs = [0.0, 5.0, 5.8, 20.0, 50.0, 95.0, 100.0, 103.25, 110.0, 200.0, 400.0]
    res = {"force_N": F, "freqs_hz": freqs, "variants": {}}
    for v in ("eq1", "as_printed"):
        rows = []
        for f in freqs:
            X = np.linalg.solve(k_terms(2 * pi * f, v), np.array([-F, F], dtype=complex))
            rows.append([X[0].real, X[0].imag, X[1].real, X[1].imag])
        M = np.diag([P["m1"], P["m2"]])
        K = np.real(k_terms(0.0, v))
        lam = eigh(K, M, eigvals_only=True)
        res["variants"][v] = {"x1_re_im_x2_re_im_m": rows, "natural_rad_s": list(np.sqrt(lam))}
    return res


def main():
    check = "--check" in sys.argv
    t, Y, nfev = transient()
    # Independent second solution (RK45, rtol 1e-10, as the Rust default) to state the reference's error.
    _, Y45, _ = transient("RK45", 1e-10, np.array([1e-15, 1e-15, 1e-15, 1e-15]))
    scale = np.abs(Y[:, [0, 2]]).max()
    d45 = np.abs(Y45[:, [0, 2]] - Y[:, [0, 2]]).max()
    print(f"DOP853 rtol 1e-12: {nfev} rhs evaluations; max|x| = {scale:.4e} m; "
          f"RK45 rtol 1e-10 differs by {d45:.2e} m ({d45 / scale:.1e} of max|x|)")
    tr = {
        "description": "two-mass start-up from rest under P_em*|sin(w t)|, paper Mathcad form (eq. (1) variant)",
        "generator": "validation/two_mass_transient.py",
        "scipy": scipy.__version__, "numpy": np.__version__,
        "method": "solve_ivp DOP853 piecewise between the kinks t = k*pi/w",
        "rtol": RTOL, "atol_m_ms": list(ATOL),
        "rk45_rtol1e-10_max_abs_diff_m": d45,
        "params": dict(P, p_em=P_EM, omega_mains=W_MAINS),
        "t_s": list(t), "x1_m": list(Y[:, 0]), "x2_m": list(Y[:, 2]),
    }
    st = steady()
    st.update({"description": "steady complex amplitudes (x(t) = Im(X e^{i Omega t}), force -F on m1, +F on m2)",
               "generator": "validation/two_mass_transient.py", "params": P})
    files = {REF / "two_mass_transient.json": tr, REF / "two_mass_steady.json": st}
    if check:
        bad = False
        old = json.loads((REF / "two_mass_transient.json").read_text())
        d = max(np.abs(np.array(old["x1_m"]) - Y[:, 0]).max(), np.abs(np.array(old["x2_m"]) - Y[:, 2]).max())
        print(f"transient: max difference to committed reference {d:.2e} m")
        bad |= d > 1e-9 * scale
        old = json.loads((REF / "two_mass_steady.json").read_text())
        for v in ("eq1", "as_printed"):
            a = np.array(old["variants"][v]["x1_re_im_x2_re_im_m"])
            b = np.array(st["variants"][v]["x1_re_im_x2_re_im_m"])
            d = np.abs(a - b).max() / np.abs(b).max()
            print(f"steady {v}: max relative difference {d:.2e}")
            bad |= d > 1e-9
        sys.exit(1 if bad else 0)
    REF.mkdir(exist_ok=True)
    for path, data in files.items():
        path.write_text(json.dumps(data, indent=None, separators=(",", ":")) + "\n")
        print(f"wrote {path.relative_to(HERE.parent)}")


if __name__ == "__main__":
    main()
