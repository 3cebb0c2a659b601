#!/usr/bin/env python3
"""Checks a `spectral-render --spectral` EXR against the layout of Fichet, Pacanowski and
Wilkie 2021, "An OpenEXR Layout for Spectral Images" (JCGT 10(3)), reading it with the
`OpenEXR` Python module: the `spectralLayoutVersion` and `emissiveUnits` string attributes,
every spectral channel name against the paper's grammar (S<stokes>.<value with a comma as
decimal separator><SI prefix><m|Hz>), float32 pixels, and the bins integrated against
colour-science's CIE 1931 2° curves reproducing the XYZ layer's image mean within 1 %.

Usage: check_spectral_exr.py FILE.exr   (exit status 0 when every check passes)
"""

import re
import sys

import colour
import numpy as np
import OpenEXR

# The paper's channel-name grammar (§3.1), emissive channels: S0..S3, then the wavelength.
GRAMMAR = re.compile(
    r"^S([0-3])\.(\d*,?\d*([Ee][+-]?\d+)?)(Y|Z|E|P|T|G|M|k|h|da|d|c|m|u|n|p)?(m|Hz)$"
)
TO_NM = {"n": 1.0, "u": 1e3, "m": 1e6, "": 1e9, "p": 1e-3}
K_M = 683.0


def wavelength_nm(name):
    m = GRAMMAR.match(name)
    if not m:
        return None
    if m.group(5) != "m":
        raise SystemExit(f"{name}: frequencies are not expected")
    return float(m.group(2).replace(",", ".")) * TO_NM[m.group(4) or ""]


def main(path):
    with OpenEXR.File(path) as f:
        header = dict(f.header())
        channels = {name: np.array(c.pixels) for name, c in f.channels().items()}
    failures = []
    if header.get("spectralLayoutVersion") != "1.0":
        failures.append(f"spectralLayoutVersion = {header.get('spectralLayoutVersion')!r}")
    if header.get("emissiveUnits") != "W.m^-2.sr^-1":
        failures.append(f"emissiveUnits = {header.get('emissiveUnits')!r}")
    spectral = sorted(
        (wavelength_nm(n), n) for n in channels if n.startswith("S") and wavelength_nm(n)
    )
    odd = [n for n in channels if n.startswith("S") and wavelength_nm(n) is None]
    if odd:
        failures.append(f"channels outside the grammar: {odd}")
    if not spectral:
        failures.append("no spectral channel")
        print("\n".join(failures))
        return 1
    for _, n in spectral:
        if channels[n].dtype != np.float32:
            failures.append(f"{n} is {channels[n].dtype}, not float32")
    lo, hi, count = header["spectralRender:spectralBins"].split(",")
    lo, hi, count = float(lo), float(hi), int(count)
    width = (hi - lo) / count
    centres = [lo + width * (i + 0.5) for i in range(count)]
    got = [w for w, _ in spectral]
    if len(got) != count or max(abs(a - b) for a, b in zip(got, centres)) > 1e-4:
        failures.append(f"bin centres {got} are not those of {lo}-{hi} nm / {count}")
    # Bin-integrated CMFs at 0.01 nm (linear interpolation of colour-science's 1 nm table).
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    xs = cmfs.wavelengths
    xyz_bins = np.zeros(3)
    xyz_layer = np.array([channels[f"XYZ.{c}"].astype(np.float64).mean() for c in "XYZ"])
    for (w, n) in spectral:
        grid = np.linspace(w - width / 2, w + width / 2, int(round(width / 0.01)) + 1)
        weights = [np.trapezoid(np.interp(grid, xs, cmfs.values[:, c]), grid) for c in range(3)]
        xyz_bins += K_M * channels[n].astype(np.float64).mean() * np.array(weights)
    err = np.max(np.abs(xyz_bins / xyz_layer - 1.0))
    print(f"{len(spectral)} spectral channels, {lo:g}-{hi:g} nm")
    print(f"image mean XYZ: layer {xyz_layer}, from the bins {xyz_bins}, max rel. diff {err:.4%}")
    # The curves outside the bins' range (below 380 / above 780 nm: < 0.01 % of Y) are left
    # out; the rest is the binning error and the noise of the bins' difference from the layer.
    if err > 0.01:
        failures.append(f"the bins integrate to XYZ within {err:.4%}, not 1 %")
    if failures:
        print("\n".join(failures))
        return 1
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
