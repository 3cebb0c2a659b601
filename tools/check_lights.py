#!/usr/bin/env python3
"""Checks spectral-render's photometry against colour-science 0.4.7.

    .venv/bin/python tools/check_lights.py measured.json

Input JSON (written by tests/photometry.rs):

    {
      "illuminants": {"CIE-A": {"luminous_flux": F, "efficacy": E, "xy": [x, y],
                                "cct": T or null, "duv": D or null}, ...},
      "blackbody_2042_luminance": L,
      "color_temperature_rgb": {"2700": [r, g, b], ...},
      "report": "path of `spectral-render lights --json` output",
      "report_emission": {"/Prim/Path": "CIE-A", ...}
    }

References, all on colour-science's own 1 nm curves over 360-830 nm (tools/gen_spectra.py `aligned`,
exactly the data in spectra/):

- luminous flux: colour.luminous_flux(sd) (K_m = 683, CIE 1924 V(lambda), trapezoid) -- within 1e-4
  relative (the issue's bound) for every illuminant in spectra/illuminants/;
- efficacy: colour.luminous_efficacy(sd) -- 1e-4 relative;
- chromaticity: colour.XYZ_to_xy(colour.sd_to_XYZ(sd, cmfs, method="Integration")) -- 1e-5;
- CCT, Duv: colour.uv_to_CCT(uv) with its default method (Ohno 2013) and defaults (CMFs over 360-780 nm,
  Planck's c2 = 0.014388 m K), from colour's own uv of the SPD -- |dT| < 1 K and |dDuv| < 1e-4; and, like
  for like, colour's uv_to_CCT_Ohno2013 with the 360-830 nm CMFs, its temperature rescaled by
  c2_CODATA / 0.014388 (the locus depends on c2 / T only), to 0.05 K. Checked where |Duv| <= 0.05;
- the 2042 K blackbody's luminance: colour.luminous_flux(colour.sd_blackbody(2042, shape, c1, c2)) with
  the CODATA 2018 radiation constants c1 = 2 pi h c^2, c2 = h c / k (ours) -- 1e-5 relative; with
  colour's default constants it differs by about 2e-4 (printed); and about 6.0e5 cd/m^2 (1 %), the old
  platinum-point definition of the candela (60 cd/cm^2 at 2042 K);
- UsdLux colour temperature tint: the blackbody's linear sRGB (colour.XYZ_to_RGB, "sRGB", no encoding)
  divided channel-wise by that of 6500 K, then scaled to luminance 1 with the sRGB Y row -- 2e-3;
- the light report: each light's chromaticity, CCT and efficacy as above, for the SPD it emits.

Exit status: 0 if every check passes, 1 if not, 2 on bad input.
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

warnings.simplefilter("ignore")  # colour warns about optional packages it does not need here

sys.dont_write_bytecode = True  # no tools/__pycache__ in the work tree
sys.path.insert(0, str(Path(__file__).resolve().parent))
import colour  # noqa: E402
import numpy as np  # noqa: E402
from colour.temperature import uv_to_CCT_Ohno2013  # noqa: E402
from gen_spectra import CMFS_NAME, ILLUMINANTS, aligned  # noqa: E402

H, C, K_B = 6.62607015e-34, 299792458.0, 1.380649e-23
C1_CODATA, C2_CODATA = 2 * np.pi * H * C * C, H * C / K_B
C2_COLOUR = 0.014388
SHAPE = colour.SpectralShape(360, 830, 1)

failures: list[str] = []


def check(what: str, ours: float, ref: float, tol: float, relative: bool) -> None:
    err = abs(ours / ref - 1) if relative else abs(ours - ref)
    kind = "rel" if relative else "abs"
    ok = err <= tol
    print(f"  {'ok ' if ok else 'BAD'} {what:<44} ours {ours:<22.10g} ref {ref:<22.10g} {kind} err {err:.2e} (tol {tol:g})")
    if not ok:
        failures.append(what)


def cmfs_830():
    return aligned(colour.MSDS_CMFS[CMFS_NAME])


def chromaticity(sd) -> np.ndarray:
    return colour.XYZ_to_xy(colour.sd_to_XYZ(sd, cmfs_830(), method="Integration"))


def spd_checks(name: str, sd, ours: dict) -> None:
    """xy, CCT/Duv and efficacy of `ours` (a dict) against colour-science for `sd`."""
    xy = chromaticity(sd)
    check(f"{name} x", ours["xy"][0], xy[0], 1e-5, False)
    check(f"{name} y", ours["xy"][1], xy[1], 1e-5, False)
    check(f"{name} efficacy lm/W", ours["efficacy"], colour.luminous_efficacy(sd), 1e-4, True)
    uv = colour.xy_to_UCS_uv(xy)
    T, duv = colour.uv_to_CCT(uv)
    if abs(duv) > 0.05:
        if ours["cct"] is not None:
            failures.append(f"{name}: CCT reported although |Duv| = {abs(duv):.3f} > 0.05")
        return
    if ours["cct"] is None:
        failures.append(f"{name}: no CCT reported (colour-science: {T:.2f} K, Duv {duv:.4f})")
        return
    check(f"{name} CCT K (colour default)", ours["cct"], T, 1.0, False)
    check(f"{name} Duv (colour default)", ours["duv"], duv, 1e-4, False)
    T_830, _ = uv_to_CCT_Ohno2013(uv, cmfs_830())
    check(f"{name} CCT K (like for like)", ours["cct"], T_830 * C2_CODATA / C2_COLOUR, 0.05, False)


def illuminant_checks(illuminants: dict) -> None:
    print("illuminants in spectra/illuminants/:")
    if set(illuminants) != set(ILLUMINANTS):
        failures.append(f"illuminant set differs: {sorted(set(illuminants) ^ set(ILLUMINANTS))}")
    for stem, (key, _, _) in ILLUMINANTS.items():
        if stem not in illuminants:
            continue
        sd = aligned(colour.SDS_ILLUMINANTS[key])
        ours = illuminants[stem]
        check(f"{stem} luminous flux", ours["luminous_flux"], colour.luminous_flux(sd), 1e-4, True)
        spd_checks(stem, sd, ours)


def blackbody_checks(luminance: float) -> None:
    print("2042 K blackbody (platinum point):")
    codata = colour.sd_blackbody(2042, SHAPE, c1=C1_CODATA, c2=C2_CODATA)
    default = colour.sd_blackbody(2042, SHAPE)
    check("luminance cd/m2 (CODATA constants)", luminance, colour.luminous_flux(codata), 1e-5, True)
    ref_default = colour.luminous_flux(default)
    print(f"  info colour-science default constants: {ref_default:.6g} cd/m2, ours / it - 1 = {luminance / ref_default - 1:.2e}")
    check("luminance cd/m2 vs 6.0e5 (60 cd/cm2)", luminance, 6.0e5, 0.01, True)


def color_temperature_checks(rgbs: dict) -> None:
    print("UsdLux colour temperature tint (linear Rec.709, white at 6500 K, luminance 1):")
    y_row = colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ[1]

    def rgb(t: float) -> np.ndarray:
        XYZ = colour.sd_to_XYZ(colour.sd_blackbody(t, SHAPE), cmfs_830(), method="Integration")
        return colour.XYZ_to_RGB(XYZ, "sRGB", apply_cctf_encoding=False)

    white = rgb(6500)
    for t, ours in rgbs.items():
        rel = rgb(float(t)) / white
        ref = np.maximum(rel / np.dot(y_row, rel), 0)
        for c, name in enumerate("RGB"):
            check(f"{t} K {name}", ours[c], ref[c], 2e-3, False)


def report_checks(report_path: str, emission: dict) -> None:
    print("`spectral-render lights --json` report:")
    report = json.loads(Path(report_path).read_text())
    by_prim = {entry["prim"]: entry for entry in report["lights"]}
    for prim, stem in emission.items():
        entry = by_prim[prim]
        sd = aligned(colour.SDS_ILLUMINANTS[ILLUMINANTS[stem][0]])
        ours = {
            "xy": [entry["chromaticity"]["x"], entry["chromaticity"]["y"]],
            "efficacy": entry["luminous_efficacy_lm_w"],
            "cct": entry["cct_k"],
            "duv": entry["duv"],
        }
        spd_checks(f"{prim} ({stem})", sd, ours)


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    try:
        data = json.loads(Path(sys.argv[1]).read_text())
    except (OSError, ValueError) as e:
        print(f"check_lights.py: cannot read {sys.argv[1]}: {e}")
        return 2
    illuminant_checks(data["illuminants"])
    blackbody_checks(data["blackbody_2042_luminance"])
    color_temperature_checks(data["color_temperature_rgb"])
    report_checks(data["report"], data["report_emission"])
    if failures:
        print(f"FAILED: {len(failures)} check(s): {', '.join(failures)}")
        return 1
    print("all photometry checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
