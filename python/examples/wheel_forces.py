"""Runs a vehicle scenario from Python and plots its wheel loads Q and
lateral forces Y against the distance run (matplotlib, if installed).

    python python/examples/wheel_forces.py models/scenarios/vehicle1_tc1.ron \
        --engine symbolic -o wheel_forces.png
"""

from __future__ import annotations

import argparse
import sys

import railmbs


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scenario", help="scenario file of a model with wheel-rail contacts")
    p.add_argument("--end-time", type=float, help="run to this time instead, s")
    p.add_argument("--engine", default="numeric", choices=["numeric", "symbolic"])
    p.add_argument("-o", "--output", default="wheel_forces.png", help="image file")
    args = p.parse_args(argv)

    sc = railmbs.Scenario.load(args.scenario)
    if args.end_time is not None:
        sc.end_time = args.end_time
    r = sc.run(engine=args.engine, progress=lambda t, t_end: print(f"\r{t:8.3f} / {t_end} s", end="", file=sys.stderr))
    print(file=sys.stderr)
    s = r["s[m]"]
    loads = [c for c in r.columns if c.endswith(".Q [N]")]
    lateral = [c for c in r.columns if c.endswith(".Y [N]")]
    print(f"{r}: {len(loads)} wheel loads, {len(lateral)} lateral forces over {s[0]:.1f}..{s[-1]:.1f} m")
    print(r.assessment().to_string(index=False))
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return 0
    fig, (ax_q, ax_y) = plt.subplots(2, 1, sharex=True, figsize=(9, 6))
    for c in loads:
        ax_q.plot(s, r[c] / 1e3, label=c.replace(" [N]", ""))
    for c in lateral:
        ax_y.plot(s, r[c] / 1e3, label=c.replace(" [N]", ""))
    ax_q.set_ylabel("Q [kN]")
    ax_y.set_ylabel("Y [kN]")
    ax_y.set_xlabel("distance s [m]")
    ax_q.legend(fontsize="x-small", ncol=2)
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
