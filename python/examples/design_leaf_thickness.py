"""A design loop over the leaf thickness.

For each thickness of the S3 leaf, the leaf's stiffness (fixed–guided, hex20) and the first
frequency of the leaf carrying a 11.34 kg mass on its guided end, against the beam formulas
(k ∝ h³, f = √(k/m)/2π): the thickness for a target frequency is read off the curve. Writes
design_leaf_thickness.png.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import vibrofem as vf
from _common import out_dir

E, NU, L, B, MASS = 2.1e11, 0.3, 0.169, 0.146, 11.34


def main() -> None:
    out = out_dir()
    hs = np.array([0.005, 0.007, 0.009, 0.011, 0.013])
    k, f1 = [], []
    for h in hs:
        mesh = vf.read_mesh(f"box:{L},{B},{h}:16,6,2:hex20")
        leaf = vf.Model(mesh, fix=["xmin"], couple={"xmax": "z"}, point_mass={"xmax": MASS})
        k.append(leaf.static(force={"xmax": (0, 0, 1000)}).stiffness["xmax"])
        modes = leaf.modes(1)
        f1.append(modes.frequencies_hz[0])
        print(f"h = {h * 1e3:4.1f} mm: k = {k[-1]:.4e} N/m, f1 = {f1[-1]:7.2f} Hz")
    kb = E * B * hs**3 / L**3
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
    a1.loglog(hs * 1e3, np.array(k) / 1e6, "o-", label="vibrofem")
    a1.loglog(hs * 1e3, kb / 1e6, "--", color="grey", label="beam E b h³/l³")
    a1.set_xlabel("leaf thickness (mm)")
    a1.set_ylabel("stiffness (MN/m)")
    a1.legend()
    a2.plot(hs * 1e3, f1, "o-", label="vibrofem, first mode")
    a2.plot(hs * 1e3, np.sqrt(kb / MASS) / (2 * np.pi), "--", color="grey", label="√(k_beam/m)/2π")
    a2.set_xlabel("leaf thickness (mm)")
    a2.set_ylabel("frequency with 11.34 kg (Hz)")
    a2.legend()
    fig.tight_layout()
    png = out / "design_leaf_thickness.png"
    fig.savefig(png, dpi=110)
    print("wrote", png)


if __name__ == "__main__":
    main()
