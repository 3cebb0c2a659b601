#!/usr/bin/env python3
"""Generates the reference spectral data in spectra/ and scenes/colorchecker.usda.

Run from anywhere (paths are resolved from this file):

    tools/venv.sh && .venv/bin/python tools/gen_spectra.py          # (re)write everything
    .venv/bin/python tools/gen_spectra.py --check                   # verify the files match

Every colour-science curve is aligned to 1 nm over 360-830 nm *by colour-science itself*
(``sd.copy().align(colour.SpectralShape(360, 830, 1))`` with its default interpolator and
extrapolator), so the renderer (which interpolates the 1 nm grid linearly) and the Python
reference checks (tools/check_colorchecker.py) use identical numbers.

Metals are copied from ``<repo>/../shared/data/nk`` (refractiveindex.info, CC0) with licence and
units lines added; glasses are Sellmeier coefficients from their datasheets (constants below).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from decimal import Decimal
from pathlib import Path

warnings.simplefilter("ignore")  # colour warns about optional packages it does not need here

import colour  # noqa: E402
import numpy as np  # noqa: E402
from colour.algebra import CubicSplineInterpolator, SpragueInterpolator  # noqa: E402
from colour.colorimetry import SDS_LEFS_PHOTOPIC  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
SPECTRA = REPO / "spectra"
SCENE = REPO / "scenes" / "colorchecker.usda"
NK_DIR = REPO.parent / "shared" / "data" / "nk"

SHAPE = colour.SpectralShape(360, 830, 1)
COLOUR = f"colour-science {colour.__version__}"
EXPECTED_COLOUR = "0.4.7"

CMFS_NAME = "CIE 1931 2 Degree Standard Observer"
V_NAME = "CIE 1924 Photopic Standard Observer"
CHECKER_NAME = "BabelColor Average"

#: colour-science patch name -> our file stem (spectra/colorchecker/<stem>.csv), in chart order.
COLORCHECKER_STEMS = {
    "dark skin": "dark_skin",
    "light skin": "light_skin",
    "blue sky": "blue_sky",
    "foliage": "foliage",
    "blue flower": "blue_flower",
    "bluish green": "bluish_green",
    "orange": "orange",
    "purplish blue": "purplish_blue",
    "moderate red": "moderate_red",
    "purple": "purple",
    "yellow green": "yellow_green",
    "orange yellow": "orange_yellow",
    "blue": "blue",
    "green": "green",
    "red": "red",
    "yellow": "yellow",
    "magenta": "magenta",
    "cyan": "cyan",
    "white 9.5 (.05 D)": "white_9_5",
    "neutral 8 (.23 D)": "neutral_8",
    "neutral 6.5 (.44 D)": "neutral_6_5",
    "neutral 5 (.70 D)": "neutral_5",
    "neutral 3.5 (1.05 D)": "neutral_3_5",
    "black 2 (1.5 D)": "black_2",
}

#: our file stem -> (colour-science key, what it is, published source).
ILLUMINANTS = {
    "CIE-A": ("A", "CIE standard illuminant A", "CIE 015:2018 / ISO 11664-2"),
    "CIE-D50": ("D50", "CIE illuminant D50", "CIE 015:2018"),
    "CIE-D65": ("D65", "CIE standard illuminant D65", "CIE 015:2018 / ISO 11664-2"),
    **{f"CIE-F{i}": (f"FL{i}", f"CIE fluorescent illuminant F{i}", "CIE 015:2018") for i in range(1, 13)},
    **{f"LED-B{i}": (f"LED-B{i}", f"CIE phosphor-type LED illuminant LED-B{i}", "CIE 015:2018") for i in range(1, 6)},
}

#: Sellmeier coefficients: stem -> (B1..B3, C1..C3 in um^2, source lines).
GLASSES = {
    "BK7": (
        ["1.03961212", "0.231792344", "1.01046945"],
        ["0.00600069867", "0.0200179144", "103.560653"],
        [
            "SCHOTT N-BK7 (517642.251) optical glass datasheet, SCHOTT AG, Sellmeier dispersion formula coefficients",
            "licence: published material constants (facts, not copyrightable); no restrictions",
        ],
    ),
    "fused_silica": (
        ["0.6961663", "0.4079426", "0.8974794"],
        [str(Decimal(c) ** 2) for c in ("0.0684043", "0.1162414", "9.896161")],
        [
            "I. H. Malitson, 'Interspecimen Comparison of the Refractive Index of Fused Silica', "
            "J. Opt. Soc. Am. 55, 1205-1209 (1965); C_i = lambda_i^2 with lambda_i = 0.0684043, 0.1162414, 9.896161 um",
            "licence: published material constants (facts, not copyrightable); no restrictions",
        ],
    ),
}

LICENCE_COLOUR = (
    "licence: colour-science is BSD-3-Clause (Colour Developers); the CIE tables are published "
    "reference data (CIE 015:2018)"
)


def aligned(sd: colour.SpectralDistribution | colour.MultiSpectralDistributions):
    """The curve aligned to 1 nm over 360-830 nm by colour-science itself (default interpolator
    and extrapolator), exactly as the renderer and check_colorchecker.py see it."""
    return sd.copy().align(SHAPE)


def interpolator_used(sd) -> str:
    """Names the interpolator `align` picks (mirrors SpectralDistribution.interpolate)."""
    if sd.shape == SHAPE:
        return "none needed (already tabulated at 1 nm over 360-830 nm)"
    if sd.interpolator not in (SpragueInterpolator, CubicSplineInterpolator):
        name = sd.interpolator.__name__
    elif sd.is_uniform():
        name = SpragueInterpolator.__name__
    else:
        name = CubicSplineInterpolator.__name__
    method = sd.extrapolator_kwargs.get("method", "Constant")
    return f"{name} inside the native range, {sd.extrapolator.__name__} method '{method}' (end values held) outside it"


def sampling_line(sd) -> str:
    s = sd.shape
    return (
        f"sampling: native {s.start:g}-{s.end:g} nm every {s.interval:g} nm; aligned to 1 nm over 360-830 nm by "
        f"colour-science itself: sd.copy().align(colour.SpectralShape(360, 830, 1)) -> {interpolator_used(sd)}; "
        "the renderer interpolates this 1 nm grid linearly"
    )


def fmt(v: float) -> str:
    return f"{float(v):.10g}"


def table_text(comments: list[str], header: str, rows) -> str:
    lines = [f"# {c}" for c in comments]
    lines.append(header)
    lines += [",".join(fmt(v) if not isinstance(v, str) else v for v in row) for row in rows]
    return "\n".join(lines) + "\n"


def sd_rows(sd):
    a = aligned(sd)
    vals = a.values if a.values.ndim == 2 else a.values[:, None]
    return [[int(w), *v] for w, v in zip(a.wavelengths, vals)]


def cie_files() -> dict[str, str]:
    cmfs = colour.MSDS_CMFS[CMFS_NAME]
    v = SDS_LEFS_PHOTOPIC[V_NAME]
    return {
        "cie/cie1931_2deg.csv": table_text(
            [
                "CIE 1931 2 degree standard observer colour-matching functions x_bar, y_bar, z_bar",
                f"source: CIE 015:2018 via {COLOUR} `colour.MSDS_CMFS['{CMFS_NAME}']`",
                LICENCE_COLOUR,
                "units: nm; x_bar, y_bar, z_bar dimensionless (y_bar = V(lambda), 1 at 555 nm)",
                sampling_line(cmfs),
                "generated by tools/gen_spectra.py",
            ],
            "nm,x_bar,y_bar,z_bar",
            sd_rows(cmfs),
        ),
        "cie/cie1924_photopic.csv": table_text(
            [
                "CIE 1924 photopic luminous efficiency function V(lambda)",
                f"source: CIE 015:2018 / ISO 23539:2005 via {COLOUR} "
                f"`colour.colorimetry.SDS_LEFS_PHOTOPIC['{V_NAME}']`",
                LICENCE_COLOUR,
                "units: nm; v dimensionless, 1 at 555 nm",
                sampling_line(v),
                "generated by tools/gen_spectra.py",
            ],
            "nm,v",
            sd_rows(v),
        ),
    }


def illuminant_files() -> dict[str, str]:
    out = {}
    for stem, (key, what, published) in ILLUMINANTS.items():
        sd = colour.SDS_ILLUMINANTS[key]
        out[f"illuminants/{stem}.csv"] = table_text(
            [
                what,
                f"source: {published} via {COLOUR} `colour.SDS_ILLUMINANTS['{key}']`",
                LICENCE_COLOUR,
                "units: nm; value = relative spectral power distribution, unitless, "
                "as published (A and D series normalised to 100 at 560 nm)",
                sampling_line(sd),
                "generated by tools/gen_spectra.py",
            ],
            "nm,value",
            sd_rows(sd),
        )
    return out


def colorchecker_files() -> dict[str, str]:
    sds = colour.SDS_COLOURCHECKERS[CHECKER_NAME]
    if list(sds.keys()) != list(COLORCHECKER_STEMS):
        raise SystemExit(f"colour's '{CHECKER_NAME}' patch names changed: {list(sds.keys())}")
    out = {}
    for i, (name, stem) in enumerate(COLORCHECKER_STEMS.items()):
        sd = sds[name]
        out[f"colorchecker/{stem}.csv"] = table_text(
            [
                f"X-Rite ColorChecker Classic patch {i + 1} of 24, '{name}': mean spectral reflectance",
                "source: BabelColor ColorChecker averages (D. Pascale, BabelColor, 'ColorChecker data', 2012; "
                f"average of 30 charts) via {COLOUR} `colour.SDS_COLOURCHECKERS['{CHECKER_NAME}']['{name}']`",
                "licence: colour-science is BSD-3-Clause (Colour Developers), which redistributes the BabelColor "
                "averages published freely by BabelColor",
                "units: nm; reflectance unitless in [0, 1]",
                sampling_line(sd),
                "generated by tools/gen_spectra.py",
            ],
            "nm,reflectance",
            sd_rows(sd),
        )
    return out


def metal_files() -> dict[str, str]:
    out = {}
    if not NK_DIR.is_dir():
        print(f"note: {NK_DIR} not found; keeping spectra/metal/ as it is", file=sys.stderr)
        return out
    for src in sorted(NK_DIR.glob("*.csv")):
        lines = src.read_text().splitlines()
        comments = [ln for ln in lines if ln.startswith("#")]
        body = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
        if body[0] != "wavelength_nm,n,k":
            raise SystemExit(f"{src}: unexpected header {body[0]!r}")
        extra = [
            "# licence: CC0 1.0 (public domain dedication of the refractiveindex.info database)",
            "# units: wavelength_nm in nm; n and k dimensionless (complex index n + i k)",
            "# sampling: as tabulated by the source (irregular); the renderer resamples linearly to 1 nm and "
            "holds the end values outside the table",
            "# copied by tools/gen_spectra.py from shared/data/nk",
        ]
        out[f"metal/{src.stem}.csv"] = "\n".join(comments + extra + body) + "\n"
    return out


def glass_files() -> dict[str, str]:
    out = {}
    for stem, (b, c, source) in GLASSES.items():
        out[f"glass/{stem}.csv"] = table_text(
            [
                f"{stem}: Sellmeier dispersion coefficients, n^2(lambda) = 1 + sum_i B_i lambda^2 / (lambda^2 - C_i)",
                f"source: {source[0]}",
                source[1],
                "units: B_i dimensionless; C_i in um^2; lambda in um (the renderer divides its wavelength in nm by 1000)",
                "sampling: not sampled; the renderer evaluates the formula at each wavelength (src/spectral/sellmeier.rs)",
                "generated by tools/gen_spectra.py",
            ],
            "i,B,C_um2",
            [[str(i + 1), b[i], c[i]] for i in range(3)],
        )
    return out


# ------------------------------------------------------------------------------------------------
# scenes/colorchecker.usda

PATCH = 0.05  # m
PITCH = 0.06  # m


def scene_text() -> str:
    stems = list(COLORCHECKER_STEMS.values())
    h = PATCH / 2
    grid = "\n".join(
        "#   " + " ".join(f"{stems[r * 6 + c]:>13}" for c in range(6)) for r in range(4)
    )
    meshes, looks = [], []
    for i, stem in enumerate(stems):
        r, c = divmod(i, 6)
        x, y = (c - 2.5) * PITCH, (1.5 - r) * PITCH
        pts = [(x - h, y - h), (x + h, y - h), (x + h, y + h), (x - h, y + h)]
        p = ", ".join(f"({px:.4f}, {py:.4f}, 0)" for px, py in pts)
        meshes.append(
            f'''        def Mesh "{stem}" (
            prepend apiSchemas = ["MaterialBindingAPI"]
        )
        {{
            # patch {i + 1}: row {r}, column {c}, centre ({x:.2f}, {y:.2f}, 0) m
            uniform bool doubleSided = 0
            float3[] extent = [({x - h:.4f}, {y - h:.4f}, 0), ({x + h:.4f}, {y + h:.4f}, 0)]
            int[] faceVertexCounts = [3, 3]
            int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]
            point3f[] points = [{p}]
            normal3f[] normals = [(0, 0, 1), (0, 0, 1), (0, 0, 1), (0, 0, 1)] (
                interpolation = "vertex"
            )
            uniform token orientation = "rightHanded"
            uniform token subdivisionScheme = "none"
            rel material:binding = </World/Looks/{stem}>
        }}
'''
        )
        looks.append(
            f'''        def Material "{stem}"
        {{
            token outputs:surface.connect = </World/Looks/{stem}/Diffuse.outputs:surface>

            def Shader "Diffuse"
            {{
                uniform token info:id = "spectral:diffuse"
                uniform token inputs:reflectance:spectrum = "colorchecker/{stem}"
                token outputs:surface
            }}
        }}
'''
        )
    return f'''#usda 1.0
(
    defaultPrim = "World"
    doc = "ColorChecker Classic (BabelColor average spectra) under a uniform D65 dome. Generated by tools/gen_spectra.py."
    metersPerUnit = 1
    renderSettingsPrimPath = "/Render/Settings"
    upAxis = "Y"
)

# Layout (metres, Y up, chart in the z = 0 plane facing +Z, seen from the camera at (0, 0, 1)):
# 24 patches of {PATCH} m x {PATCH} m on a {PITCH} m pitch, in colour-science's order
# (colour.SDS_COLOURCHECKERS['{CHECKER_NAME}']); patch i is at row r = i / 6 from the top and
# column c = i % 6 from the left, centred at x = (c - 2.5) * {PITCH}, y = (1.5 - r) * {PITCH}:
#
{grid}
#
# Each patch is a Lambertian spectral:diffuse whose reflectance is the tabulated spectrum
# spectra/colorchecker/<name>.csv. The dome is uniform D65 white (colour (1, 1, 1)) of luminance
# 100 cd/m2, so a patch of reflectance rho(lambda) has radiance rho(lambda) * D65n(lambda) * 100
# (D65n = D65 normalised to 1 cd/m2), i.e. the reference that tools/check_colorchecker.py computes
# with luminance L = 100.
# Camera: pinhole at (0, 0, 1) looking down -Z, horizontal half-width 0.2 m at the chart
# (20.955 / 2 / 52.3875 = 0.2), 240 x 160 pixels (3:2), so each patch spans about 30 x 30 pixels.

def Xform "World"
{{
    def Xform "ColorChecker"
    {{
{chr(10).join(meshes)}    }}

    def Scope "Looks"
    {{
{chr(10).join(looks)}    }}

    def DomeLight "Dome"
    {{
        float inputs:intensity = 100
    }}

    def Camera "Camera"
    {{
        float2 clippingRange = (0.01, 100)
        float focalLength = 52.3875
        float horizontalAperture = 20.955
        token projection = "perspective"
        float verticalAperture = 13.97
        double3 xformOp:translate = (0, 0, 1)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }}
}}

def Scope "Render"
{{
    def RenderSettings "Settings"
    {{
        rel camera = </World/Camera>
        uniform int2 resolution = (240, 160)
    }}
}}
'''


def validate_scene(path: Path) -> None:
    """Opens the stage with usd-core and checks the pieces tools and tests rely on."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise SystemExit(f"{path}: usd-core could not open the stage")
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == 24, len(meshes)
    shaders = [p for p in stage.Traverse() if p.GetTypeName() == "Shader"]
    tokens = {p.GetAttribute("inputs:reflectance:spectrum").Get() for p in shaders}
    assert tokens == {f"colorchecker/{s}" for s in COLORCHECKER_STEMS.values()}, tokens
    for p in shaders:
        assert (SPECTRA / f"{p.GetAttribute('inputs:reflectance:spectrum').Get()}.csv").is_file()
    assert stage.GetPrimAtPath("/World/Dome").GetAttribute("inputs:intensity").Get() == 100
    settings = stage.GetPrimAtPath("/Render/Settings")
    assert settings.GetRelationship("camera").GetTargets()[0] == "/World/Camera"


# ------------------------------------------------------------------------------------------------


def all_files() -> dict[Path, str]:
    files = {}
    for group in (cie_files, illuminant_files, colorchecker_files, metal_files, glass_files):
        files.update({SPECTRA / k: v for k, v in group().items()})
    files[SCENE] = scene_text()
    return files


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="verify the files instead of writing them")
    args = ap.parse_args()
    if colour.__version__ != EXPECTED_COLOUR:
        print(f"error: need colour-science {EXPECTED_COLOUR}, have {colour.__version__}", file=sys.stderr)
        return 1
    files = all_files()
    if args.check:
        stale = [p for p, text in files.items() if not p.is_file() or p.read_text() != text]
        for p in stale:
            print(f"out of date: {p.relative_to(REPO)}", file=sys.stderr)
        validate_scene(SCENE)
        print(f"{len(files) - len(stale)} of {len(files)} files up to date")
        return 1 if stale else 0
    for path, text in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    validate_scene(SCENE)
    print(f"wrote {len(files)} files under {REPO}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
