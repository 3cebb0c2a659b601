#!/usr/bin/env python3
"""Designs the reflectance pair of scenes/metamers.usda (pure Python, no dependencies).

Patch "Grey" is a flat reflectance of 0.45. Patch "Metamer" is the grey plus a metameric
black of the D65-weighted CIE 1931 2-degree colour-matching functions (Wyszecki and Stiles,
"Color Science", 2nd ed., section 3.8.5: a spectrum whose tristimulus values under the
illuminant are zero), sampled every 10 nm over 360-830 nm: the pair matches under D65 and
not under illuminants with another spectral shape. The knots are piecewise linear, as the
renderer interpolates `inputs:reflectance:samples`; the integrals here use that same 1 nm
interpolation, so the match holds for the spectra the renderer sees. Prints the samples for
the stage and the predicted CIEDE2000 per illuminant (white: the illuminant's own).

    python3 tools/gen_metamers.py
"""
import math
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "spectra")
NM = list(range(360, 831))
KNOTS = list(range(360, 831, 10))


def table(path):
    rows = {}
    for line in open(os.path.join(ROOT, path)):
        if line.startswith("#") or line.startswith("nm"):
            continue
        v = [float(x) for x in line.strip().split(",")]
        rows[int(v[0])] = v[1:]
    return rows


CMF = table("cie/cie1931_2deg.csv")


def illuminant(name):
    t = table("illuminants/%s.csv" % name)
    return [t[n][0] for n in NM]


def dense(knots):
    """The 1 nm values of a piecewise-linear spectrum with values `knots` at KNOTS."""
    out = []
    for n in NM:
        i = min((n - 360) // 10, len(KNOTS) - 2)
        f = (n - KNOTS[i]) / 10.0
        out.append(knots[i] * (1 - f) + knots[i + 1] * f)
    return out


def xyz(refl, spd):
    k = 100.0 / sum(s * CMF[n][1] for n, s in zip(NM, spd))
    return [k * sum(r * s * CMF[n][c] for n, r, s in zip(NM, refl, spd)) for c in range(3)]


def lab(p, white):
    def f(t):
        return t ** (1 / 3) if t > (6 / 29) ** 3 else t / (3 * (6 / 29) ** 2) + 4 / 29
    fx, fy, fz = (f(p[c] / white[c]) for c in range(3))
    return [116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)]


def de2000(l1, l2):
    """CIEDE2000 (Sharma, Wu and Dalal 2005, eqs. 1-17), kL = kC = kH = 1."""
    L1, a1, b1 = l1
    L2, a2, b2 = l2
    cbar = (math.hypot(a1, b1) + math.hypot(a2, b2)) / 2
    g = 0.5 * (1 - math.sqrt(cbar ** 7 / (cbar ** 7 + 25 ** 7)))
    a1p, a2p = a1 * (1 + g), a2 * (1 + g)
    c1p, c2p = math.hypot(a1p, b1), math.hypot(a2p, b2)
    h1p = math.degrees(math.atan2(b1, a1p)) % 360 if c1p else 0.0
    h2p = math.degrees(math.atan2(b2, a2p)) % 360 if c2p else 0.0
    dl, dc = L2 - L1, c2p - c1p
    dh = 0.0
    if c1p * c2p:
        dh = h2p - h1p
        dh -= 360 if dh > 180 else 0
        dh += 360 if dh < -180 else 0
    dH = 2 * math.sqrt(c1p * c2p) * math.sin(math.radians(dh / 2))
    lbar, cbarp = (L1 + L2) / 2, (c1p + c2p) / 2
    hbar = h1p + h2p
    if c1p * c2p:
        hbar = (hbar + (360 if abs(h1p - h2p) > 180 else 0)) / 2
        hbar -= 360 if hbar >= 360 else 0
    t = (1 - 0.17 * math.cos(math.radians(hbar - 30)) + 0.24 * math.cos(math.radians(2 * hbar))
         + 0.32 * math.cos(math.radians(3 * hbar + 6)) - 0.20 * math.cos(math.radians(4 * hbar - 63)))
    sl = 1 + 0.015 * (lbar - 50) ** 2 / math.sqrt(20 + (lbar - 50) ** 2)
    sc, sh = 1 + 0.045 * cbarp, 1 + 0.015 * cbarp * t
    rt = (-2 * math.sqrt(cbarp ** 7 / (cbarp ** 7 + 25 ** 7))
          * math.sin(math.radians(60 * math.exp(-(((hbar - 275) / 25) ** 2)))))
    return math.sqrt((dl / sl) ** 2 + (dc / sc) ** 2 + (dH / sh) ** 2 + rt * (dc / sc) * (dH / sh))


def solve3(m, v):
    det = lambda a: (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
                     - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
                     + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    d = det(m)
    out = []
    for c in range(3):
        mc = [row[:] for row in m]
        for r in range(3):
            mc[r][c] = v[r]
        out.append(det(mc) / d)
    return out


def metameric_black(spd, shape):
    """`shape` (knot values) minus its projection on the rows of M, M the 3 x knots matrix
    of the D65-weighted CMF integrals of the piecewise-linear basis."""
    basis = []
    for i in range(len(KNOTS)):
        e = [0.0] * len(KNOTS)
        e[i] = 1.0
        d = dense(e)
        basis.append([sum(r * s * CMF[n][c] for n, r, s in zip(NM, d, spd)) for c in range(3)])
    m = [[basis[i][c] for i in range(len(KNOTS))] for c in range(3)]
    mmt = [[sum(m[a][i] * m[b][i] for i in range(len(KNOTS))) for b in range(3)] for a in range(3)]
    mv = [sum(m[a][i] * shape[i] for i in range(len(KNOTS))) for a in range(3)]
    y = solve3(mmt, mv)
    return [shape[i] - sum(m[a][i] * y[a] for a in range(3)) for i in range(len(KNOTS))]


def main():
    d65 = illuminant("CIE-D65")
    grey = [0.45] * len(KNOTS)
    # Two periods over the visible range: reflects more near 450 and 600 nm, less between.
    shape = [math.cos(2 * math.pi * (n - 450) / 150) if 400 <= n <= 700 else 0.0 for n in KNOTS]
    black = metameric_black(d65, shape)
    k = 0.40 / max(abs(b) for b in black)
    metamer = [g + k * b for g, b in zip(grey, black)]
    print("grey    reflectance:samples = [%s]" % ", ".join("(%d, %.4f)" % (n, v) for n, v in zip(KNOTS, grey)))
    print("metamer reflectance:samples = [%s]" % ", ".join("(%d, %.4f)" % (n, v) for n, v in zip(KNOTS, metamer)))
    # The stage holds the values rounded to 4 decimals: the prediction uses those.
    metamer = [round(v, 4) for v in metamer]
    for name in ["CIE-D65", "CIE-A", "CIE-F11", "LED-B3"]:
        spd = illuminant(name)
        white = xyz([1.0] * len(NM), spd)
        a, b = xyz(dense(grey), spd), xyz(dense(metamer), spd)
        print("%-8s dE00 = %.3f" % (name, de2000(lab(a, white), lab(b, white))))


if __name__ == "__main__":
    main()
