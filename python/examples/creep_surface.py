"""Creep-force surface of a contact patch: the tangential force over a grid
of longitudinal and lateral creepages, by any creep law, from numpy arrays
(one call for the whole grid).

    python python/examples/creep_surface.py --law fastsim-a:20 -n 61 -o creep.png
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from railmbs import contact


def surface(law: str, n: int):
    """Creepages (ξ, η) on an n × n grid and |F|/(μN) there, for a tread
    contact a = 6 mm, b = 4 mm, N = 80 kN, μ = 0.3, no spin."""
    xi, eta = np.meshgrid(np.linspace(-5e-3, 5e-3, n), np.linspace(-5e-3, 5e-3, n))
    fx, fy, _ = contact.creep_forces(law, 6e-3, 4e-3, 80e3, xi, eta, 0.0, friction=0.3)
    return xi, eta, np.hypot(fx, fy) / (0.3 * 80e3)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--law", default="fastsim-a", help="creep law, as umsim creep --method")
    p.add_argument("-n", type=int, default=41, help="grid points per creepage")
    p.add_argument("-o", "--output", default="creep_surface.png", help="image file")
    args = p.parse_args(argv)
    xi, eta, f = surface(args.law, args.n)
    print(f"{contact.creep_law_name(args.law)}: |F|/(μN) from {f.min():.3f} to {f.max():.3f} on {f.size} cases")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return 0
    fig, ax = plt.subplots(subplot_kw={"projection": "3d"}, figsize=(7, 5))
    ax.plot_surface(xi * 1e3, eta * 1e3, f, cmap="viridis")
    ax.set_xlabel("ξ [‰]")
    ax.set_ylabel("η [‰]")
    ax.set_zlabel("|F| / μN [-]")
    ax.set_title(args.law)
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
