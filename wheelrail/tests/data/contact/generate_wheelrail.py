#!/usr/bin/env python3
"""Generate s1002_uic60_patches.csv and s1002_uic60_strips.csv: CONTACT's
non-Hertzian normal contact of an S1002 wheel on a UIC60 rail (1:40).

Usage:  generate_wheelrail.py CONTACT_EXE PROFILE_DIR OUT_DIR

CONTACT_EXE is CONTACT's stand-alone program (built outside this repository,
see README.md); PROFILE_DIR holds the Manchester benchmark profiles
MBench_S1002_v3.prw and MBench_UIC60_v3.prr (models/profiles/). Each case is
CONTACT's module 1 (wheel-rail), the left wheel of a wheelset (back-to-back
1360 mm, taping line 70 mm from the flange back, nominal radius 460 mm) on a
track of gauge 1435 mm measured 14 mm below the rail top, no cant, at lateral
shift Y_WS (CONTACT's track frame: y to the right, so Y_WS < 0 moves the left
wheel towards its flange), no roll, no yaw, vertical force 10 kN prescribed,
normal problem only (T = 0), identical elastic bodies G = 82 GPa, nu = 0.28,
planar contact per patch (D = 2), elements 0.1 x 0.1 mm.

Written per patch (s1002_uic60_patches.csv): CONTACT's contact reference
point, contact angle, normal force, approach, maximum pressure, contact area
(elements in contact x element area); per patch and element row across the
patch (s1002_uic60_strips.csv): the row's lateral coordinate in the patch's
tangent plane, the leading and trailing x of its contact elements' outer
edges, the row's largest pressure and its force (sum of pressure x element
area). Units: mm, N, N/mm^2 (MPa), rad.

Two-point contact: CONTACT (this build) combines the tread and flange-root
regions of a two-point contact into one patch with one tangent plane (its
separation of patches by angle, A_SEP < 90 deg, stopped the gfortran build);
the test splits such a patch into its separate regions by the rows
(s1002_uic60_strips.csv), whose forces give each region's load.
"""
import csv, os, re, subprocess, sys, tempfile

SHIFTS = [0.0, -2.0, -4.0, -5.0, -5.04, -5.08, -5.1, -5.12, -5.16, -5.5, -6.0, -6.5, -7.0, -8.0]  # Y_WS, mm
FZ = 10000.0    # N
DX = 0.1        # mm, element size in x and s

INPUT = """  1 MODULE
 0200100    C-P-B-T-N-F-S   CONFIG, PVTIME, BOUND,  TANG,   NORM,   FORCE,  STRESS
 0022033    V-L-D-C-M-Z-E   VARFRC, FRCLAW, DISCNS, INFLCF, MATER,  ZTRACK, EWHEEL
 0001321    H-G-I-A-O-W-R     HEAT, GAUSEI, IESTIM, MATFIL, OUTPUT, FLOW,   RETURN
    999     100    30    1     1e-5         MAXGS , MAXIN , MAXNR , MAXOUT, EPS
  0.300   0.300                                 FSTAT, FKIN
  0.280   0.280   82000.  82000.                POISS 1,2,  GG 1,2
  {dx:.3f}   {dx:.3f}   1.000   90d   8.0   4.0       DX,DS, DQREL, A_SEP, D_SEP, D_COMB
   14.0     0    1435.0   0.000                GAUGHT, GAUGSQ, GAUGWD, CANT
  'MBench_UIC60_v3.prr'   0     1.0   0.0       RFNAME, MIRRORY, SCALE, SMOOTH
     0.0    0.0   0.000   0.0   0.0   0.000     DY, DZ, ROLL, VY, VZ, VROLL
  1360.0  -70.0   460.0                         FBDIST, FBPOS, NOMRAD
  'MBench_S1002_v3.prw'   0     1.0   0.0       WFNAME, MIRRORY, SCALE, SMOOTH
  0.0  {y:.4f}  {fz:.1f}  0.0  0.0  0.0      S, Y, FZ, ROLL, YAW, PITCH
 2000. 0.0    0.0   0.0        0.0  -4.34811810 VS,VY,VZ, VROLL,VYAW,VPITCH
 0 MODULE
"""

NUM = r'[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?'


def after(lines, i, header):
    """Numbers on the line after the first line from i containing header."""
    while header not in lines[i]:
        i += 1
    return [float(v) for v in re.findall(NUM, lines[i + 1])], i + 1


def run(exe, profile_dir, y):
    d = tempfile.mkdtemp()
    for f in ['MBench_S1002_v3.prw', 'MBench_UIC60_v3.prr']:
        os.symlink(os.path.abspath(os.path.join(profile_dir, f)), os.path.join(d, f))
    with open(os.path.join(d, 'case.inp'), 'w') as f:
        f.write(INPUT.format(dx=DX, y=y, fz=FZ))
    subprocess.run([exe, '2', 'case'], cwd=d, check=True, capture_output=True)
    lines = open(os.path.join(d, 'case.out')).read().split('\n')
    z_ws, _ = after(lines, 0, 'S_WS        Y_WS        Z_WS')
    patches = []
    for i, l in enumerate(lines):
        m = re.search(r'DATA FOR CONTACT PATCH\s+(\d+)', l)
        if not m:
            continue
        k = int(m.group(1))
        loc, j = after(lines, i, 'XCP(TR)     YCP(TR)')
        wloc, j = after(lines, j, 'XCP(W)      YCP(W)')
        tot, j = after(lines, j, 'FN          FX')
        tot2, j = after(lines, j, 'APPROACH     PMAX')
        stat, j = after(lines, j, 'NPOT   NCON')
        patch = dict(patch=k, ycp_tr=loc[1], zcp_tr=loc[2], delta=loc[3], ycp_r=loc[4],
                     zcp_r=loc[5], ycp_w=wloc[1], zcp_w=wloc[2], fn=tot[0],
                     approach=tot2[3], pmax=tot2[4], ncon=int(stat[1]),
                     area=stat[1] * DX * DX)
        patch['strips'] = strips(os.path.join(d, 'case.%04d%s.mat' % (1, 'abcdefgh'[k - 1])))
        patches.append(patch)
    return z_ws[2], patches


def strips(mat):
    """Per element row iy (lateral): s centre, leading/trailing x edge, max pressure, force."""
    rows = [l for l in open(mat) if l.strip()]
    head = [float(v) for v in re.findall(NUM, rows[7])]
    mx, xl, yl, dx, dy = int(head[0]), head[2], head[3], head[4], head[5]
    out = {}
    for l in rows[13:]:
        v = l.split()
        if len(v) < 5 or v[0].startswith('%'):
            continue
        i, igs, pn = int(v[0]), int(v[1]), float(v[4])
        if igs < 1 or pn <= 0.0:
            continue
        ix, iy = (i - 1) % mx, (i - 1) // mx
        x0, x1 = xl + ix * dx, xl + (ix + 1) * dx
        s = yl + (iy + 0.5) * dy
        if iy in out:
            a, b, _, p, f = out[iy]
            out[iy] = (min(a, x0), max(b, x1), s, max(p, pn), f + pn * dx * dy)
        else:
            out[iy] = (x0, x1, s, pn, pn * dx * dy)
    return [out[k] for k in sorted(out)]


def main():
    exe, profile_dir, out_dir = sys.argv[1:4]
    with open(os.path.join(out_dir, 's1002_uic60_patches.csv'), 'w', newline='') as fp, \
         open(os.path.join(out_dir, 's1002_uic60_strips.csv'), 'w', newline='') as fs:
        wp, ws = csv.writer(fp), csv.writer(fs)
        wp.writerow(['y_ws', 'z_ws', 'patch', 'ycp_tr', 'zcp_tr', 'delta', 'ycp_r', 'zcp_r',
                     'ycp_w', 'zcp_w', 'fn', 'approach', 'pmax', 'ncon', 'area'])
        ws.writerow(['y_ws', 'patch', 's', 'x_trail', 'x_lead', 'p_row_max', 'f_row'])
        for y in SHIFTS:
            z, patches = run(exe, profile_dir, y)
            for p in patches:
                wp.writerow([y, z, p['patch'], p['ycp_tr'], p['zcp_tr'], p['delta'], p['ycp_r'],
                             p['zcp_r'], p['ycp_w'], p['zcp_w'], p['fn'], p['approach'],
                             p['pmax'], p['ncon'], '%.4f' % p['area']])
                for x0, x1, s, pm, f in p['strips']:
                    ws.writerow([y, p['patch'], '%.4f' % s, '%.4f' % x0, '%.4f' % x1, pm,
                                 '%.5g' % f])
            print(y, z, [(p['patch'], p['fn'], p['area'], p['pmax'], p['delta']) for p in patches])


main()
