"""A leaf spring's stiffness and stress.

The S3 leaf (169 × 146 × 9 mm steel, hex20) is clamped at x = 0 and its far face is guided along z
through a rigid coupling; 1 kN on the coupling gives the stiffness, between the fixed-guided beam
(k = E b h³ / l³) and the plate (÷ (1 − ν²)) formulas, and the von Mises stress along the top
surface, highest at the clamp and at the guided end (the fixed-guided beam's moment M = F l / 2 at
both ends). Writes spring_stiffness.png.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import vibrofem as vf
from _common import out_dir

E, NU, L, B, H = 2.1e11, 0.3, 0.169, 0.146, 0.009


def main() -> None:
    out = out_dir()
    mesh = vf.read_mesh(f"box:{L},{B},{H}:24,8,2:hex20")
    leaf = vf.Model(mesh, material=(E, NU, 7850.0), fix=["xmin"], couple={"xmax": "z"})
    st = leaf.static(force={"xmax": (0, 0, 1000)})
    k = st.stiffness["xmax"]
    kb = E * B * H**3 / L**3
    print(f"k = {k:.4e} N/m; beam {kb:.4e}, plate {kb / (1 - NU**2):.4e}")
    x, y, z = mesh.nodes.T
    top = np.isclose(z, H) & np.isclose(y, B / 2, atol=B / 16)
    order = np.argsort(x[top])
    sigma_beam = 6 * 1000 * (L / 2 - x) / (B * H**2)  # fixed-guided beam: M(x) = F (l/2 − x)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
    a1.bar(["beam\nE b h³/l³", "vibrofem\nhex20", "plate\n÷(1−ν²)"], [kb / 1e6, k / 1e6, kb / (1 - NU**2) / 1e6],
           color=["#bbb", "#1f77b4", "#bbb"])
    a1.set_ylabel("stiffness (MN/m)")
    a1.set_title("leaf spring, fixed–guided")
    a2.plot(x[top][order] * 1e3, st.von_mises[top][order] / 1e6, "o-", ms=3, label="vibrofem, top surface")
    a2.plot(np.sort(x) * 1e3, np.abs(sigma_beam[np.argsort(x)]) / 1e6, "--", color="grey", label="beam |6M/(b h²)|")
    a2.set_xlabel("x (mm)")
    a2.set_ylabel("von Mises (MPa) under 1 kN")
    a2.legend()
    fig.tight_layout()
    png = out / "spring_stiffness.png"
    fig.savefig(png, dpi=110)
    print("wrote", png)


if __name__ == "__main__":
    main()
