"""An EN 14363-style sensitivity study of Manchester Vehicle 1: primary yaw
stiffness × equivalent conicity × running speed, reduced to the largest
Y/Q and |ΣY|, drawn as heat maps (matplotlib, if installed).

    python python/examples/en14363_sensitivity.py \
        [--study models/studies/vehicle1_en14363_sensitivity.ron] \
        [-o out/en14363] [--jobs 2] [--dask 2]

The study file varies the primary longitudinal stiffness ``kx`` of every
axlebox (a wheelset's primary yaw stiffness against its bogie frame is
2·kx·b1², b1 = 1 m) and the flange back distance ``fbd`` of every wheelset,
which with the track's 1435 mm gauge sets the equivalent conicity of S1002
on UIC60 1:40. The conicity of each ``fbd`` is computed here by EN 15302
(``railmbs.contact.equivalent_conicity`` at a wheelset amplitude of 3 mm,
the reference amplitude of EN 14363), so the heat maps' axis is the
equivalent conicity. The study's results go to ``OUTPUT/results.csv`` (rerun
to resume); the heat-map data to ``OUTPUT/heatmap.csv`` (one row per case:
speed, yaw stiffness, conicity, max Y/Q, max |ΣY|); the picture to
``OUTPUT/heatmap.png``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import railmbs
import railmbs.study as rs

REPO = Path(__file__).resolve().parents[2]
STUDY = REPO / "models" / "studies" / "vehicle1_en14363_sensitivity.ron"
PROFILES = REPO / "models" / "profiles"
# Vehicle 1's lateral semi-spacing of the primary springs b1, m
# (models/vehicles/components/bogie_vehicle1.ron).
B1 = 1.0
# EN 14363 judges the equivalent conicity at a wheelset amplitude of 3 mm.
AMPLITUDE = 3e-3


def conicity(flange_back: float) -> float:
    """Equivalent conicity (EN 15302, 3 mm amplitude) of Vehicle 1's S1002
    wheels on UIC60 1:40 rails (gauge 1.435 m, 0.46 m wheels) with the
    flange back distance ``flange_back`` (m)."""
    wheel = railmbs.contact.read_profile(PROFILES / "MBench_S1002_v3.prw")
    # The benchmark rail file is drawn inclined (1:40): read as it is.
    rail = railmbs.contact.read_profile(PROFILES / "MBench_UIC60_v3.ban")
    lam = railmbs.contact.equivalent_conicity(
        wheel, rail, [AMPLITUDE], gauge=1.435, flange_back=flange_back, radius=0.46
    )
    return float(lam[0])


def heatmap_table(df):
    """The heat-map data of a result table: one row per case that ran, with
    ``speed[m/s]``, ``kyaw[MNm/rad]`` (2·kx·b1² per wheelset), ``fbd[m]``,
    ``conicity`` (EN 15302 at 3 mm), ``YQ.max`` and ``sumY.max[kN]``."""
    import pandas as pd

    ok = df[df["status"] == "ok"]
    lam = {f: conicity(f) for f in sorted(ok["fbd"].unique())}
    return pd.DataFrame(
        {
            "speed[m/s]": ok["@speed"].to_numpy(),
            "kyaw[MNm/rad]": 2 * ok["kx"].to_numpy() * B1**2 / 1e6,
            "fbd[m]": ok["fbd"].to_numpy(),
            "conicity": [lam[f] for f in ok["fbd"]],
            "YQ.max": ok["YQ.max"].to_numpy(),
            "sumY.max[kN]": ok["sumY.max[N]"].to_numpy() / 1e3,
        }
    ).sort_values(["speed[m/s]", "kyaw[MNm/rad]", "conicity"], kind="stable").reset_index(drop=True)


def grids(table, speed: float, quantity: str):
    """The heat map of ``quantity`` at ``speed``: (yaw stiffnesses, conicities,
    values[i_stiffness, j_conicity]); NaN where a case failed."""
    at = table[table["speed[m/s]"] == speed]
    ks = np.sort(at["kyaw[MNm/rad]"].unique())
    lams = np.sort(at["conicity"].unique())
    z = np.full((len(ks), len(lams)), np.nan)
    for _, r in at.iterrows():
        z[np.searchsorted(ks, r["kyaw[MNm/rad]"]), np.searchsorted(lams, r["conicity"])] = r[quantity]
    return ks, lams, z


def plot(table, path: Path) -> bool:
    """Heat maps of max Y/Q and max |ΣY| over yaw stiffness × conicity, one
    column per speed. False when matplotlib is not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    speeds = sorted(table["speed[m/s]"].unique())
    quantities = [("YQ.max", "max Y/Q (2 m sliding mean)"), ("sumY.max[kN]", "max |ΣY| [kN]")]
    fig, axes = plt.subplots(len(quantities), len(speeds), figsize=(4.2 * len(speeds), 3.6 * len(quantities)),
                             squeeze=False)
    for col, v in enumerate(speeds):
        for row, (q, label) in enumerate(quantities):
            ax = axes[row][col]
            ks, lams, z = grids(table, v, q)
            # One colour scale per quantity across the speeds.
            im = ax.imshow(z, origin="lower", aspect="auto", cmap="viridis",
                           vmin=table[q].min(), vmax=table[q].max())
            ax.set_xticks(range(len(lams)), [f"{x:.3f}" for x in lams])
            ax.set_yticks(range(len(ks)), [f"{k:.0f}" for k in ks])
            for i in range(len(ks)):
                for j in range(len(lams)):
                    if np.isfinite(z[i, j]):
                        ax.text(j, i, f"{z[i, j]:.3f}" if q == "YQ.max" else f"{z[i, j]:.2f}",
                                ha="center", va="center", color="w", fontsize="small")
            ax.set_xlabel("equivalent conicity (EN 15302, 3 mm)")
            ax.set_ylabel("primary yaw stiffness [MN·m/rad]")
            ax.set_title(f"{label}, {v:g} m/s", fontsize="medium")
            fig.colorbar(im, ax=ax)
    fig.suptitle("Vehicle 1 on track case 1 (R 150 m): EN 14363 sensitivity")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return True


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--study", default=str(STUDY), help="study file (its grid over kx, fbd and @speed)")
    p.add_argument("-o", "--output", default="out/en14363", help="output folder")
    p.add_argument("--jobs", type=int, default=None, help="threads of the local pool (default: all cores)")
    p.add_argument("--dask", type=int, default=0, metavar="N",
                   help="run on a Dask LocalCluster of N worker processes instead")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    out = Path(args.output)
    if args.dask:
        from dask.distributed import Client, LocalCluster

        with LocalCluster(n_workers=args.dask, threads_per_worker=1, host="127.0.0.1",
                          dashboard_address=None) as cluster, Client(cluster) as client:
            df = rs.run(args.study, out, backend=client, progress=not args.no_progress)
    else:
        df = rs.run(args.study, out, jobs=args.jobs, progress=not args.no_progress)
    failed = df[df["status"] != "ok"]
    for _, r in failed.iterrows():
        print(f"case {r['index']} ({r['case_id']}) failed: {r['error']}")
    table = heatmap_table(df)
    table.to_csv(out / "heatmap.csv", index=False)
    print(f"{len(df)} cases, {len(failed)} failed; heat-map data in {out / 'heatmap.csv'}")
    print(table.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    if plot(table, out / "heatmap.png"):
        print(f"wrote {out / 'heatmap.png'}")
    else:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
