"""The peer of issue 19: the planar chain of N links (models/tools/gen_chains.py)
with CasADi's generated C for M(q) and the bias h(q, q̇) = k − Q_g, integrated
10 s by classical RK4 at 1 ms in a plain C loop with a naive Cholesky
solve per stage (a benchmark, not a test).

    python python/bench/casadi_chain.py [--links 10 30] [--callgrind] [--keep DIR]

Needs ``pip install casadi`` (any 3.x) and a C compiler (``cc``, -O2). The
equations are Lagrange's, derived by CasADi's automatic differentiation from
the chain's kinetic and potential energy: links of 1 kg and 1 m, centre of
mass at mid-link, Izz = 1/12 kg m², revolute joints about z with relative
angles, gravity 9.81 m/s² along −y, q0 = (0.5, 0, …), q̇0 = 0 (the models of
models/mechanisms/chainN.ron). Prints the final q0 (to compare with
``umsim run models/scenarios/chainN_rk4.ron``), the CPU time of the loop
(median of 3 runs) and, with ``--callgrind``, the instruction count of the
whole process (``valgrind --tool=callgrind``; the loop is nearly all of it).
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


def run(n: int, work: Path, callgrind: bool) -> dict:
    work.mkdir(parents=True, exist_ok=True)
    gen = ca.CodeGenerator("chain.c", {"with_header": True})
    gen.add(chain_function(n))
    gen.generate(str(work) + "/")
    (work / "main.c").write_text(MAIN_C % {"n": n})
    exe = work / f"chain{n}"
    subprocess.run(
        ["cc", "-O2", "-o", str(exe), "main.c", "chain.c", "-lm"], cwd=work, check=True
    )
    times, q0 = [], None
    for _ in range(3):
        out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
        fields = dict(line.split() for line in out.strip().splitlines())
        times.append(float(fields["cpu_s"]))
        q0 = fields["q0"]
    result = {"links": n, "cpu_s": statistics.median(times), "q0_end": q0}
    if callgrind:
        cg = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={work}/cg.out", str(exe)],
            capture_output=True,
            text=True,
            check=True,
        )
        m = re.search(r"Collected : (\d+)", cg.stderr)
        result["instructions"] = int(m.group(1)) if m else None
    return result


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--links", type=int, nargs="+", default=[10, 30])
    p.add_argument("--callgrind", action="store_true", help="count instructions too")
    p.add_argument("--keep", type=Path, help="keep the generated C in this directory")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = a.keep or Path(tmp)
        for n in a.links:
            r = run(n, base / f"chain{n}", a.callgrind)
            ins = f"  {r['instructions'] / 1e6:.0f} M instructions" if "instructions" in r else ""
            print(f"chain{n}: cpu {r['cpu_s']:.4f} s{ins}  q0(10 s) = {r['q0_end']}")


if __name__ == "__main__":
    main()
