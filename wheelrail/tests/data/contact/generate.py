#!/usr/bin/env python3
"""Generate hertz_creep.csv: exact-theory creep forces from Vollebregt's CONTACT.

Usage:  generate.py CONTACT_EXE UMSIM_EXE OUT.csv [MX]

CONTACT_EXE is CONTACT's stand-alone program (built outside this repository,
see README.md); UMSIM_EXE is railmbs' `umsim`, used only to choose the case
inputs: Kalker's linear coefficients scale each creepage to the fraction of
full sliding it is meant to reach (the reference values are CONTACT's alone).
Each case is a Hertzian ellipse with prescribed semi-axes (IPOTCN = -3) and
normal force, steady rolling with prescribed creepages, Coulomb friction,
identical elastic bodies, MX x MX elements over 1.05 x the ellipse.
"""
import csv, math, os, subprocess, sys, tempfile

G, NU, MU = 8e10, 0.28, 0.3           # Pa, -, -
SCALE = 1.05                          # potential contact / ellipse
# (a, b, N): semi-axes in the rolling and lateral direction (m), load (N)
PATCHES = [
    (0.006, 0.004, 80000.0),    # tread, a/b = 1.5 (models/creep/cases.csv)
    (0.005, 0.005, 60000.0),    # circle
    (0.008, 0.0032, 100000.0),  # long tread patch, a/b = 2.5
    (0.002, 0.005, 20000.0),    # flange, a/b = 0.4 (models/creep/cases.csv)
    (0.0015, 0.0075, 30000.0),  # narrow flange, a/b = 0.2
]
LEVELS = [0.1, 0.3, 0.6, 1.0, 2.0, 5.0]  # linear force / (mu N)


def kalker_unit(umsim, a, b, n):
    """Linear-theory Fx/xi, Fy/eta, Fy/phi (N, N, N m) of railmbs' Kalker law."""
    with tempfile.NamedTemporaryFile('w', suffix='.csv', delete=False) as f:
        f.write('a,b,G,nu,mu,N,xi,eta,phi\n')
        for xi, eta, phi in [(1e-9, 0, 0), (0, 1e-9, 0), (0, 0, 1e-9)]:
            f.write(f'{a},{b},{G},{NU},{MU},{n},{xi},{eta},{phi}\n')
    out = subprocess.run([umsim, 'creep', '--method', 'kalker', '--cases', f.name],
                         check=True, capture_output=True, text=True).stdout.split('\n')
    os.unlink(f.name)
    rows = [list(map(float, l.split(','))) for l in out[1:4]]
    return abs(rows[0][0]) / 1e-9, abs(rows[1][1]) / 1e-9, abs(rows[2][1]) / 1e-9


def cases(umsim):
    for a, b, n in PATCHES:
        kx, ky, ks = kalker_unit(umsim, a, b, n)
        mun = MU * n
        xi = lambda s: s * mun / kx
        eta = lambda s: s * mun / ky
        phi = lambda s: s * mun / ks
        for s in LEVELS:
            yield a, b, n, xi(s), 0.0, 0.0
            yield a, b, n, 0.0, eta(s), 0.0
            yield a, b, n, xi(s / math.sqrt(2)), eta(s / math.sqrt(2)), 0.0
            yield a, b, n, 0.0, 0.0, phi(s)
        for s in [0.3, 1.0, 3.0]:
            for sp in [0.5, 2.0]:
                yield a, b, n, 0.0, eta(s), phi(sp * s)
                yield a, b, n, 0.0, eta(s), -phi(sp * s)
                yield a, b, n, xi(s), 0.0, phi(sp * s)
                yield a, b, n, xi(s / 2), -eta(s / 2), phi(sp * s)


# CONTACT's approximate methods on the same cases (columns METHOD.Fx, ...):
# (name, M digit, B digit, slope-reduction line or None). K0 = ALFA = BETA = 1
# means no slope reduction. B = 3 is FASTSIM's parabolic traction bound.
APPROX = [
    ('contact-fastsim', 3, 3, '1.0  1.0  1.0'),
    ('contact-fastrip', 6, 0, None),
    ('contact-fastrip-modified', 5, 0, '1.0  1.0  1.0'),
]


def contact_input(rows, mx, m_digit=0, b_digit=0, slope=None):
    g = G / 1e6  # N/mm^2
    out = []
    for a, b, n, xi, eta, phi in rows:
        out.append(f''' 3 MODULE
  2{b_digit}3100     P-B-T-N-F-S        PVTIME, BOUND , TANG  , NORM , FORCE, STRESS
  022{m_digit}20     L-D-C-M-Z-E        FRCLAW, DISCNS, INFLCF, MATER, RZNORM, EXRHS
 0000141   H-G-I-A-O-W-R  HEAT, GAUSEI, IESTIM, MATFIL, OUTPUT, FLOW, RETURN
   999  2000   30    1      1e-7    MAXGS , MAXIN , MAXNR , MAXOUT, EPS
 {n:.10g}  {xi:.10g}  {eta:.10g}  {phi / 1000:.10g}     FN, CKSI, CETA, CPHI
   {MU}  {MU}                                     FSTAT, FKIN
   0.000      0.500      10000.                     CHI, DQ, VELOC
   {NU}  {NU}  {g:.10g}  {g:.10g}                 POISS 1,2,  GG 1,2
{'' if slope is None else '   ' + slope + '       K0_MF,ALFAMF,BETAMF' + chr(10)}   -3                                               IPOTCN
   {mx}  {mx}  {a * 1000:.10g}  {b * 1000:.10g}  {SCALE}      MX,MY,AA,BB,SCALE

''')
    out.append(' 0 MODULE\n')
    return ''.join(out)


def parse(text):
    lines = text.split('\n')
    res = []
    for i, l in enumerate(lines):
        if l.split()[:4] == ['FN', 'FX', 'FY', 'MZ']:
            fn, fx, fy, mz = map(float, lines[i + 1].split()[:4])
            res.append((fn, fx, fy, mz))
    return res


def main():
    exe, umsim, out = sys.argv[1:4]
    mx = int(sys.argv[4]) if len(sys.argv) > 4 else 40
    rows = list(cases(umsim))
    if len(sys.argv) > 5:  # a subset, for the discretisation check: 1-based case numbers
        keep = [int(k) for k in sys.argv[5].split(',')]
        rows = [rows[k - 1] for k in keep]
    results = []
    for m_digit, b_digit, slope in [(0, 0, None)] + [x[1:] for x in APPROX]:
        with tempfile.TemporaryDirectory() as d:
            open(os.path.join(d, 'hertz.inp'), 'w').write(
                contact_input(rows, mx, m_digit, b_digit, slope))
            subprocess.run([exe, '2', 'hertz'], cwd=d, check=True, capture_output=True)
            res = parse(open(os.path.join(d, 'hertz.out')).read())
        assert len(res) == len(rows), (m_digit, len(res), len(rows))
        results.append(res)
    with open(out, 'w', newline='') as f:
        f.write('# Exact-theory creep forces (CONTACT, Kalker\'s theory): see README.md.\n'
                '# Inputs a,b (m), G (Pa), nu, mu, N (N), xi, eta (-), phi (1/m); outputs\n'
                '# Fx, Fy (N), Mz (N m) on the wheel, CONTACT\'s sign convention.\n')
        w = csv.writer(f, lineterminator='\n')
        head = ['case', 'a', 'b', 'G', 'nu', 'mu', 'N', 'xi', 'eta', 'phi', 'Fx', 'Fy', 'Mz']
        for name, *_ in APPROX:
            head += [f'{name}.Fx', f'{name}.Fy', f'{name}.Mz']
        w.writerow(head)
        for k, (a, b, n, xi, eta, phi) in enumerate(rows, 1):
            rec = [k, a, b, G, NU, MU, n, f'{xi:.6e}', f'{eta:.6e}', f'{phi:.6e}']
            for res in results:
                fn, fx, fy, mz = res[k - 1]
                assert abs(fn - n) <= 1e-3 * n, (k, fn, n)
                rec += [f'{fx:.4e}', f'{fy:.4e}', f'{mz / 1000:.4e}']
            w.writerow(rec)


if __name__ == '__main__':
    main()
