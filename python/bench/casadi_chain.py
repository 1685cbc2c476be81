"""The peer of issue 19: the planar chain of N links (models/tools/gen_chains.py)
with CasADi's generated C for M(q) and the bias h(q, q̇) = k − Q_g, integrated
10 s by classical RK4 at 1 ms in a plain C loop with a naive Cholesky
solve per stage, and with ``--ours`` railmbs's own run of the same chain
beside it (a benchmark, not a test).

    python python/bench/casadi_chain.py [--links 10 30] [--callgrind] [--keep DIR]
        [--ours target/release/umsim] [--repeat 3]

Needs ``pip install casadi`` (any 3.x) and a C compiler (``cc``, -O2). The
equations are CasADi's automatic derivatives of the chain's kinematics (the
Jacobian form of ``chain_function``): links of 1 kg and 1 m, centre of
mass at mid-link, Izz = 1/12 kg m², revolute joints about z with relative
angles, gravity 9.81 m/s² along −y, q0 = (0.5, 0, …), q̇0 = 0 (the models of
models/mechanisms/chainN.ron). Prints the final q0, the CPU time of the
loop (median of ``--repeat`` runs) and, with ``--callgrind``, instruction
counts (``valgrind --tool=callgrind``) of the whole process and of the loop
alone (``--toggle-collect=main`` for the C program, whose ``main`` is the
loop).

With ``--ours UMSIM`` the same chain runs through ``UMSIM run
models/scenarios/chainN_rk4.ron`` with a portable symbolic plugin (``umgen
--portable``, beside UMSIM), in the same process of this script, CPU times
interleaved with CasADi's. Three output settings, since CasADi's loop
writes nothing: ``csv`` (the scenario's 1001 rows every 10 ms to a file),
``rows`` (the same rows evaluated, not written) and ``end`` (one row at
10 s). Its CPU time is the run's (``CPU time`` of the summary, set-up and
plugin loading excluded); the loop's instructions are those of
``--toggle-collect='*Runner::segment*'`` (the integration with its output
rows).
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

MAIN_C = r"""
#include <math.h>
#include <stdio.h>
#include <time.h>
#include "chain.h"
#define N %(n)d

static double M[N * N], h[N];

/* q̈ = M⁻¹(−h) by a naive Cholesky factorization (row-major, lower). */
static void accel(const double *q, const double *v, double *a) {
  const double *arg[2] = {q, v};
  double *res[2] = {M, h};
  casadi_int iw[64];
  double w[4096];
  chain(arg, res, iw, w, 0);
  for (int j = 0; j < N; j++) {
    double s = M[j * N + j];
    for (int k = 0; k < j; k++) s -= M[j * N + k] * M[j * N + k];
    double d = sqrt(s);
    M[j * N + j] = d;
    for (int i = j + 1; i < N; i++) {
      double t = M[i * N + j];
      for (int k = 0; k < j; k++) t -= M[i * N + k] * M[j * N + k];
      M[i * N + j] = t / d;
    }
  }
  for (int i = 0; i < N; i++) {
    double t = -h[i];
    for (int k = 0; k < i; k++) t -= M[i * N + k] * a[k];
    a[i] = t / M[i * N + i];
  }
  for (int i = N - 1; i >= 0; i--) {
    double t = a[i];
    for (int k = i + 1; k < N; k++) t -= M[k * N + i] * a[k];
    a[i] = t / M[i * N + i];
  }
}

int main(void) {
  double q[N] = {0}, v[N] = {0}, qs[N], vs[N], a1[N], a2[N], a3[N], a4[N];
  double v2[N], v3[N], v4[N];
  const double dt = 1e-3;
  q[0] = 0.5;
  clock_t c0 = clock();
  for (int step = 0; step < 10000; step++) {
    accel(q, v, a1);
    for (int i = 0; i < N; i++) { qs[i] = q[i] + 0.5 * dt * v[i]; v2[i] = v[i] + 0.5 * dt * a1[i]; }
    accel(qs, v2, a2);
    for (int i = 0; i < N; i++) { qs[i] = q[i] + 0.5 * dt * v2[i]; v3[i] = v[i] + 0.5 * dt * a2[i]; }
    accel(qs, v3, a3);
    for (int i = 0; i < N; i++) { qs[i] = q[i] + dt * v3[i]; v4[i] = v[i] + dt * a3[i]; }
    accel(qs, v4, a4);
    for (int i = 0; i < N; i++) {
      q[i] += dt / 6 * (v[i] + 2 * v2[i] + 2 * v3[i] + v4[i]);
      v[i] += dt / 6 * (a1[i] + 2 * a2[i] + 2 * a3[i] + a4[i]);
    }
  }
  (void)vs;
  printf("cpu_s %%.6f\nq0 %%.15e\n", (double)(clock() - c0) / CLOCKS_PER_SEC, q[0]);
  return 0;
}
"""


def chain_function(n: int) -> ca.Function:
    """M(q) (row-major dense) and h(q, q̇) = k − Q_g of the chain, in the
    Jacobian form M = Σ m JᵢᵀJᵢ + Izz jᵢᵀjᵢ, h = Σ Jᵢᵀ m (J̇ᵢq̇ + g e_y)
    (Jᵢ the Jacobian of link i's centre of mass, jᵢ of its angle), which
    CasADi's automatic differentiation evaluates with its common
    subexpressions shared."""
    q = ca.SX.sym("q", n)
    v = ca.SX.sym("v", n)
    theta = 0
    joint = ca.vertcat(0, 0)
    mass = ca.SX.zeros(n, n)
    bias = ca.SX.zeros(n, 1)
    for i in range(n):
        theta = theta + q[i]
        e = ca.vertcat(ca.sin(theta), -ca.cos(theta))
        com = joint + 0.5 * e
        jac = ca.jacobian(com, q)
        jth = ca.jacobian(theta, q)
        com_v = ca.mtimes(jac, v)
        acc_bias = ca.mtimes(ca.jacobian(com_v, q), v)
        mass += ca.mtimes(jac.T, jac) + (1.0 / 12) * ca.mtimes(jth.T, jth)
        bias += ca.mtimes(jac.T, acc_bias + ca.vertcat(0, 9.81))
        joint = joint + e
    mass_rows = ca.reshape(mass.T, n * n, 1)  # row-major
    return ca.Function("chain", [q, v], [ca.densify(mass_rows), bias], {"cse": True})


def collected(cmd: list[str], out: Path, toggle: str | None = None) -> int:
    """Instructions callgrind counts for `cmd` (all of the process, or only
    inside the functions matching `toggle`)."""
    extra = [f"--toggle-collect={toggle}"] if toggle else []
    cg = subprocess.run(
        ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *extra, *cmd],
        capture_output=True,
        text=True,
        check=True,
    )
    m = re.search(r"Collected : (\d+)", cg.stderr)
    if not m:
        raise RuntimeError(f"no instruction count from callgrind: {cg.stderr[-500:]}")
    return int(m.group(1))


def build_casadi(n: int, work: Path) -> Path:
    """CasADi's generated C and the RK4 loop, compiled; the executable."""
    work.mkdir(parents=True, exist_ok=True)
    gen = ca.CodeGenerator("chain.c", {"with_header": True})
    gen.add(chain_function(n))
    gen.generate(str(work) + "/")
    (work / "main.c").write_text(MAIN_C % {"n": n})
    exe = work / f"chain{n}"
    subprocess.run(
        ["cc", "-O2", "-o", str(exe), "main.c", "chain.c", "-lm"], cwd=work, check=True
    )
    return exe


def casadi_once(exe: Path) -> tuple[float, str]:
    """CPU time of the loop, s, and the final q0 of one run."""
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    fields = dict(line.split() for line in out.strip().splitlines())
    return float(fields["cpu_s"]), fields["q0"]


class Ours:
    """railmbs's run of the chain: the portable plugin and the scenario
    variants of the three output settings."""

    def __init__(self, umsim: Path, n: int, work: Path):
        self.umsim = umsim
        self.work = work
        root = Path(__file__).resolve().parents[2]
        model = root / f"models/mechanisms/chain{n}.ron"
        scenario = root / f"models/scenarios/chain{n}_rk4.ron"
        self.plugin = work / f"chain{n}_portable.so"
        subprocess.run(
            [str(umsim.parent / "umgen"), str(model), "--portable", "-o", str(self.plugin)],
            capture_output=True,
            check=True,
        )
        text = scenario.read_text().replace(f'"../mechanisms/chain{n}.ron"', f'"{model}"')
        once = work / f"chain{n}_end.ron"
        once.write_text(text.replace("interval: 0.01", "interval: 10.0"))
        self.csv = work / f"chain{n}.csv"
        self.variants = {
            "csv": [str(scenario), "-o", str(self.csv)],
            "rows": [str(scenario)],
            "end": [str(once)],
        }

    def command(self, variant: str) -> list[str]:
        return [str(self.umsim), "run", *self.variants[variant], "--plugin", str(self.plugin)]

    def once(self, variant: str) -> float:
        """CPU time of the run, s."""
        out = subprocess.run(
            self.command(variant), capture_output=True, text=True, check=True
        ).stdout
        m = re.search(r"^CPU time +([0-9.]+) s", out, re.M)
        if not m:
            raise RuntimeError(f"no CPU time in the summary of umsim run: {out}")
        return float(m.group(1))

    def final_q0(self) -> str:
        lines = self.csv.read_text().strip().splitlines()
        column = lines[0].split(",").index("q0")
        return lines[-1].split(",")[column]


def run(n: int, work: Path, callgrind: bool, umsim: Path | None, repeat: int) -> dict:
    exe = build_casadi(n, work)
    ours = Ours(umsim, n, work) if umsim else None
    # Interleaved, so that both sides see the same load of the machine.
    times: dict[str, list[float]] = {"casadi": []}
    q0 = None
    for _ in range(repeat):
        cpu, q0 = casadi_once(exe)
        times["casadi"].append(cpu)
        if ours:
            for variant in ours.variants:
                times.setdefault(variant, []).append(ours.once(variant))
    result = {
        "links": n,
        "cpu_s": {k: statistics.median(v) for k, v in times.items()},
        "q0_end": q0,
    }
    if ours:
        result["ours_q0_end"] = ours.final_q0()
    if callgrind:
        result["instructions"] = {
            "casadi": (collected([str(exe)], work / "cg.out"),
                       collected([str(exe)], work / "cg_loop.out", "main")),
        }
        if ours:
            for variant in ours.variants:
                cmd = ours.command(variant)
                result["instructions"][variant] = (
                    collected(cmd, work / f"cg_{variant}.out"),
                    collected(cmd, work / f"cg_{variant}_loop.out", "*Runner::segment*"),
                )
    return result


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--links", type=int, nargs="+", default=[10, 30])
    p.add_argument("--callgrind", action="store_true", help="count instructions too")
    p.add_argument("--keep", type=Path, help="keep the generated C in this directory")
    p.add_argument("--ours", type=Path, help="railmbs's umsim, run beside CasADi's loop")
    p.add_argument("--repeat", type=int, default=3, help="runs per CPU time (median)")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = (a.keep or Path(tmp)).resolve()
        umsim = a.ours.resolve() if a.ours else None
        for n in a.links:
            r = run(n, base / f"chain{n}", a.callgrind, umsim, a.repeat)
            print(f"chain{n}: q0(10 s) = {r['q0_end']} (CasADi)", end="")
            if "ours_q0_end" in r:
                print(f", {r['ours_q0_end']} (railmbs)", end="")
            print()
            print(f"  {'':8} {'CPU s':>8} {'whole M instr':>14} {'loop M instr':>13}")
            for side, cpu in r["cpu_s"].items():
                name = side if side == "casadi" else f"ours-{side}"
                ins = r.get("instructions", {}).get(side)
                counts = f" {ins[0] / 1e6:14.1f} {ins[1] / 1e6:13.1f}" if ins else ""
                print(f"  {name:8} {cpu:8.4f}{counts}")


if __name__ == "__main__":
    main()
