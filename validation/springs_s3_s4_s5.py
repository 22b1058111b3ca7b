#!/usr/bin/env python3
"""Convergence tables of the spring checks S3 (leaf stiffness and stress), S4 (leaf + reduced
mass frequency) and S5 (coil isolator stiffness), run with the vibrofem Python package
(``pip install ./python``) on built-in meshes (``box:`` hex20 leaves, ``helix:`` beam coils; no
files needed).

    validation/.venv/bin/python validation/springs_s3_s4_s5.py

S3: leaf 169 x 146 x 9 mm, E 2.1e11, nu 0.3; clamped at x = 0 ("xmin"), the x = l face rigidly
coupled to a reference node guided along z ("xmax:guided=z"). Stiffness from Fz = 1000 N;
peak von Mises (averaged nodal) at an imposed 0.46 mm. Published FE: 1.937e-4 m, 83 MPa;
hand: k = E b h^3 / l^3 (beam) or with E/(1 - nu^2) (plate), sigma = 3 E h D / l^2 = 91.3 MPa.
S4: same leaf with density 1 kg/m^3 and 11.34 kg on the guided reference node; first mode.
Published 109.56 Hz; hand sqrt(k/m)/(2 pi) with the FE k.
S5: coil d 6 mm, D 32 mm, 6 turns, pitch 10 mm, G 7.7e10 (E = 2G(1 + nu), nu 0.3) as
Timoshenko beams along the helix, bottom end clamped, top end guided axially, Q = 600 N.
Published FE 9.96 mm; formula k = G d^4/(8 D^3 i) = 63 447 N/m at i = 6 (60 266 at i = 6.3).
Prints markdown tables.
"""

from __future__ import annotations

import argparse
import math
import sys

import vibrofem as vf


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.parse_args(argv)
    E, nu, l, w, h = 2.1e11, 0.3, 0.169, 0.146, 0.009
    kb = E * w * h**3 / l**3
    print("### S3 / S4: leaf spring 169 x 146 x 9 mm, fixed-guided\n")
    print(f"Hand: k = E b h³/l³ = {kb:.4e} N/m (δ = {1000 / kb * 1e3:.4f} mm), plate "
          f"{kb / (1 - nu**2):.4e} N/m (δ = {1000 * (1 - nu**2) / kb * 1e3:.4f} mm); σ = 3EhΔ/l² = "
          f"{3 * E * h * 0.46e-3 / l**2 / 1e6:.1f} MPa.\n")
    print("| hex20 mesh | DOFs | δ at 1000 N [mm] | k [N/m] | vs published 5.163e6 | σ_vM at 0.46 mm [MPa] "
          "| S4 f1 [Hz] | vs 109.56 | time [s] |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for d in [(6, 2, 1), (12, 4, 1), (24, 8, 2), (36, 12, 3), (48, 16, 4)]:
        mesh = vf.read_mesh(f"box:{l},{w},{h}:{d[0]},{d[1]},{d[2]}:hex20")
        leaf = vf.Model(mesh, fix=["xmin"], couple={"xmax": "z"})
        s1 = leaf.static(force={"xmax": (0, 0, 1000)})
        s2 = leaf.static(displace={"xmax": (None, None, 0.46e-3)})
        light = vf.Model(mesh, material=(E, nu, 1), fix=["xmin"], couple={"xmax": "z"}, point_mass={"xmax": 11.34})
        f1 = light.modes(1).frequencies_hz[0]
        k = s1.stiffness["xmax"]
        uz = 1000 / k
        vm = s2.von_mises.max()
        t = s1.report["timings_s"]
        print(f"| {d[0]}×{d[1]}×{d[2]} | {s1.report['dofs']} | {uz * 1e3:.4f} | {k:.4e} | {(k / 5.163e6 - 1) * 100:+.1f} % | "
              f"{vm / 1e6:.1f} | {f1:.2f} | {(f1 / 109.56 - 1) * 100:+.1f} % | {sum(t.values()):.2f} |")
    G, dw, D, i, Q = 7.7e10, 0.006, 0.032, 6.0, 600.0
    kf = G * dw**4 / (8 * D**3 * i)
    C = D / dw
    K = (4 * C - 1) / (4 * C - 4) + 0.615 / C
    tau = 8 * K * Q * D / (math.pi * dw**3)
    print(f"\n### S5: coil spring, beam helix (Timoshenko, circle d = 6 mm)\n")
    print(f"Formula k = G d⁴/(8 D³ i) = {kf:.0f} N/m at i = 6 (δ = {Q / kf * 1e3:.3f} mm at 600 N); "
          f"Wahl K = {K:.4f}, τ = 8KQD/(πd³) = {tau / 1e6:.1f} MPa.\n")
    print("| elements | elements per turn | DOFs | δ at 600 N [mm] | k [N/m] | vs formula (i = 6) | vs published FE 9.96 mm | time [s] |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for kind in ("line2", "line3"):
        for n in (6, 12, 24, 48):
            coil = vf.Model(vf.read_mesh(f"helix:{D},0.01,6,{n},{kind}"),
                            beam={"wire": f"circle:{dw}@radial:0,0,0,0,0,1"},
                            material=(2 * G * 1.3, 0.3, 7850), fix={"end_bottom": "all"},
                            couple={"end_top": "z"})
            r = coil.static(force={"end_top": (0, 0, -Q)})
            k = r.stiffness["end_top"]
            uz = Q / k
            print(f"| {kind} | {n} | {r.report['dofs']} | {uz * 1e3:.4f} | {k:.0f} | {(k / kf - 1) * 100:+.2f} % | "
                  f"{(uz / 9.96e-3 - 1) * 100:+.1f} % | {sum(r.report['timings_s'].values()):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
