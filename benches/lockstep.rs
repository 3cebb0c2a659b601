//! A measured prototype of lockstep SIMD paths (issue 18, docs/design.md §8 "Lockstep SIMD
//! paths"): the first hit of N camera samples, computed per sample as the path tracer does
//! today (scalar) and 8 samples at a time in SoA lanes (`[f32; 8]`, written so that LLVM
//! vectorises the loops over lanes), stage by stage:
//!
//! | stage | scalar (today's code) | lockstep |
//! |---|---|---|
//! | sampler | `Sampler::new` + 11 numbers per sample | the same (PCG32 stays per sample) |
//! | wavelengths | `SampledWavelengths::sample_visible` (4 `atanhf` calls) | 32 wavelengths, atanh through a polynomial ln |
//! | camera | `Camera::generate_ray` (pinhole) | the same arithmetic over 8 lanes |
//! | ray queries | `Scene::intersect`, one light sample's `Scene::occluded` | the same, per lane |
//! | light sample | `LightSampler::sample`, `Light::sample_li` | the same, per lane |
//! | shading | `Material::bsdf`, NEE `Bsdf::f`/`pdf` + power heuristic, `Bsdf::sample_f`, β | over 8 lanes: reflectance table gathers, frame, MIS, sampling |
//!
//! The shading stage runs twice each way: with the same reflectances as Lambertians
//! (`Material::Diffuse`) and with the scene's own materials when every material a hit meets
//! is an untextured UsdPreviewSurface plastic (the Cornell box's walls: a GGX coat with
//! Schlick's Fresnel over the coupled diffuse base, `bxdf/plastic.rs`). The lockstep results
//! are checked against the scalar ones (largest relative differences printed).
//!
//! Each stage is a pass over all N = width × height samples (stage-major, so each stage's
//! time is its own; the intermediate results stay in memory), timed on one thread, the
//! fastest of `--reps` passes. The lockstep side also pays the transposition of the scalar
//! stages' hits and light samples into SoA (`stage_pack`). The lockstep kernels are compiled
//! twice: for the baseline target (SSE2, 4-wide registers: an `[f32; 8]` is two of them) and
//! with `#[target_feature(enable = "avx2,fma")]` (8-wide), chosen at run time when the CPU
//! has AVX2 (the only `unsafe` here: calling those kernels after the check).
//!
//! `--occupancy` runs the path tracer's bounce loop (scalar, the scene's materials, with
//! pbrt-v4's roulette as `integrator/path.rs` and with Mitsuba 3's) on groups of 8 samples
//! (a 4×2 pixel block, one sample each; and 8 samples of one pixel) and prints, per bounce,
//! the lanes still alive and the utilisation of a masked lockstep loop.
//!
//! Instruction counts per stage: run under callgrind with `--reps 1` and read the inclusive
//! counts of the `stage_*` functions (`callgrind_annotate --inclusive=yes`).
//!
//! `cargo bench --bench lockstep [-- STAGE.usda] [--res WxH] [--reps R] [--occupancy]`;
//! default `scenes/cornell-box.usda` at 128×128 (16,384 samples), 9 reps.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use spectral_render::bxdf::CoatAlbedo;
use spectral_render::bxdf::{Bsdf, TransportMode};
use spectral_render::geometry::offset::{spawn_ray, spawn_ray_to_point};
use spectral_render::geometry::Ray;
use spectral_render::light::{LightLiSample, LightSampleContext};
use spectral_render::material::preview::PreviewLobes;
use spectral_render::material::{ColorInput, Material};
use spectral_render::sampling::{power_heuristic, Sampler};
use spectral_render::scene::{self, Hit, Scene, SurfaceHit};
use spectral_render::spectral::dense::{DenseSpectrum, DENSE_LEN};
use spectral_render::spectral::{SampledSpectrum, SampledWavelengths, Spectrum, LAMBDA_MIN};
use spectral_render::texture::TexCoord;

/// Lanes per group.
const W: usize = 8;
type F = [f32; W];
type M = [bool; W];

/// A vector per lane, structure of arrays.
#[derive(Clone, Copy, Default)]
struct V3 {
    x: F,
    y: F,
    z: F,
}

// ---------------------------------------------------------------------------------------
// Lane-wise helpers. `#[inline(always)]`, so that each kernel is compiled with its caller's
// target features.

#[inline(always)]
fn map(f: impl Fn(usize) -> f32) -> F {
    std::array::from_fn(f)
}

#[inline(always)]
fn dot(a: &V3, b: &V3) -> F {
    map(|i| a.x[i] * b.x[i] + a.y[i] * b.y[i] + a.z[i] * b.z[i])
}

/// ln x for x > 0 (Cephes `logf`: x = m 2^e with m in [√½, √2), a degree-8 polynomial in
/// m − 1; within 2 ulp of libm over the range the wavelength sampler uses, checked below).
#[inline(always)]
fn ln(x: F) -> F {
    map(|i| {
        let bits = x[i].to_bits();
        let mut e = ((bits >> 23) & 0xff) as i32 - 126;
        let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
        let small = m < std::f32::consts::FRAC_1_SQRT_2;
        e -= small as i32;
        let x = if small { m + m - 1.0 } else { m - 1.0 };
        let e = e as f32;
        let z = x * x;
        let mut y = 7.037_683_6e-2;
        for c in [
            -1.151_461e-1,
            1.167_699_9e-1,
            -1.242_014_1e-1,
            1.424_932_3e-1,
            -1.666_805_8e-1,
            2.000_071_5e-1,
            -2.499_999_4e-1,
            3.333_333e-1,
        ] {
            y = y * x + c;
        }
        y = y * x * z;
        y += -2.121_944_4e-4 * e;
        y += -0.5 * z;
        x + y + 0.693_359_4 * e
    })
}

/// sin and cos of |x| ≤ π/4 (Cephes `sinf`/`cosf` minimax polynomials on that range).
#[inline(always)]
fn sin_cos_quarter1(x: f32) -> (f32, f32) {
    let z = x * x;
    let s = x + x * z * ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1);
    let c = 1.0 - 0.5 * z + z * z * ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2);
    (s, c)
}

/// [`sin_cos_quarter1`] over the lanes.
#[inline(always)]
fn sin_cos_quarter(x: F) -> (F, F) {
    (
        map(|i| sin_cos_quarter1(x[i]).0),
        map(|i| sin_cos_quarter1(x[i]).1),
    )
}

// ---------------------------------------------------------------------------------------
// The lockstep kernels.

/// Hero wavelength sampling for 8 samples (`spectral::wavelengths`: y = 0.8569106 − 1.827502 u
/// per rotation, λ = 538 − 138.88889 atanh y, p = 0.0039398 (1 − y²)), atanh y = ½ ln((1 + y)
/// / (1 − y)). Out: λ and pdf per rotation j, lanes inside.
#[inline(always)]
fn wavelengths_kernel(u: &F, lambda: &mut [F; 4], pdf: &mut [F; 4]) {
    for j in 0..4 {
        let y = map(|i| {
            let mut up = u[i] + j as f32 * 0.25;
            if up >= 1.0 {
                up -= 1.0;
            }
            0.856_910_6 - 1.827_502 * up
        });
        let q = ln(map(|i| (1.0 + y[i]) / (1.0 - y[i])));
        lambda[j] = map(|i| (538.0 - 69.444_44 * q[i]).clamp(360.0, 830.0));
        pdf[j] = map(|i| 0.003_939_804 * (1.0 - y[i] * y[i]));
    }
}

/// The camera's affine map (row-major 3×4) and the pinhole's constants.
#[derive(Clone, Copy)]
struct PinholeK {
    m: [[f32; 4]; 3],
    sx: [f32; 2],
    sy: [f32; 2],
    near: f32,
    depth: f32,
}

/// `Camera::generate_ray` for a pinhole, 8 lanes: origin on the near plane, unit direction,
/// t_max before the far plane.
#[inline(always)]
fn camera_kernel(k: &PinholeK, fx: &F, fy: &F, o: &mut V3, d: &mut V3, t_max: &mut F) {
    let sx = map(|i| fx[i] * k.sx[0] + k.sx[1]);
    let sy = map(|i| fy[i] * k.sy[0] + k.sy[1]);
    let inv = map(|i| 1.0 / (sx[i] * sx[i] + sy[i] * sy[i] + 1.0).sqrt());
    // d_unit = (sx, sy, −1) · inv; per unit depth 1/inv.
    let local = V3 {
        x: map(|i| sx[i] * inv[i]),
        y: map(|i| sy[i] * inv[i]),
        z: map(|i| -inv[i]),
    };
    let per_depth = map(|i| 1.0 / inv[i]);
    let m = &k.m;
    let lin = |r: usize, v: &V3, i: usize| m[r][0] * v.x[i] + m[r][1] * v.y[i] + m[r][2] * v.z[i];
    let near = map(|i| k.near * per_depth[i]);
    o.x = map(|i| lin(0, &local, i) * near[i] + m[0][3]);
    o.y = map(|i| lin(1, &local, i) * near[i] + m[1][3]);
    o.z = map(|i| lin(2, &local, i) * near[i] + m[2][3]);
    let w = V3 {
        x: map(|i| lin(0, &local, i)),
        y: map(|i| lin(1, &local, i)),
        z: map(|i| lin(2, &local, i)),
    };
    let n = map(|i| 1.0 / (w.x[i] * w.x[i] + w.y[i] * w.y[i] + w.z[i] * w.z[i]).sqrt());
    *d = V3 {
        x: map(|i| w.x[i] * n[i]),
        y: map(|i| w.y[i] * n[i]),
        z: map(|i| w.z[i] * n[i]),
    };
    *t_max = map(|i| (k.depth * per_depth[i]).max(0.0));
}

/// What the shading kernel reads per lane (the hit, the path's wavelengths, the light sample
/// with its transmittance, the BSDF's random numbers), SoA.
#[derive(Clone, Copy, Default)]
struct ShadeIn {
    hit: M,
    table: [usize; W],
    ns: V3,
    wo: V3,
    lambda: [F; 4],
    light: M,
    wi_l: V3,
    l: [F; 4],
    /// pmf × solid-angle pdf of the light sample, and its transmittance.
    pdf_light: F,
    tr: F,
    u: [F; 2],
}

/// What it writes: the NEE estimate and the sampled direction with its weight f cos / p.
#[derive(Clone, Copy, Default)]
struct ShadeOut {
    nee: [F; 4],
    beta: [F; 4],
    wi: V3,
    ok: M,
}

const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// Lambertian shading for 8 lanes, the same arithmetic as `Material::bsdf` (reflectance
/// clamped to [0, 1] from its 1 nm table), `Bsdf::f`/`pdf` (f = R/π on the side of ωo,
/// pdf = |cos θi|/π), the power heuristic (Veach 1997 eq. 9.13, β = 2) and `Bsdf::sample_f`
/// (Malley's method over the concentric map, PBR 4ed §A.5.3), without the branches.
#[inline(always)]
fn shade_kernel(tables: &[&[f32; DENSE_LEN]], a: &ShadeIn, out: &mut ShadeOut) {
    // The reflectance at the 4 × 8 wavelengths: gathers from each lane's table.
    let mut rho = [[0.0f32; W]; 4];
    for (j, r) in rho.iter_mut().enumerate() {
        *r = map(|i| {
            let t = tables[a.table[i]];
            let x = a.lambda[j][i] - LAMBDA_MIN;
            let k = (x as usize).min(DENSE_LEN - 2);
            let f = x - k as f32;
            (t[k] * (1.0 - f) + t[k + 1] * f).clamp(0.0, 1.0) * INV_PI
        });
    }
    // Shading frame around ns (`Frame::from_normal`, Duff et al. 2017).
    let n = &a.ns;
    let (s, t) = frame_soa(n);
    let wo_z = dot(&a.wo, n);
    // Next-event estimation.
    let wi_z = dot(&a.wi_l, n);
    let w_nee = map(|i| {
        let pdf_bsdf = wi_z[i].abs() * INV_PI;
        let (pa, pb) = (a.pdf_light[i] * a.pdf_light[i], pdf_bsdf * pdf_bsdf);
        let live = a.hit[i] && a.light[i] && wo_z[i] * wi_z[i] > 0.0 && wo_z[i] != 0.0;
        if live && a.tr[i] > 0.0 && pa + pb > 0.0 {
            a.tr[i] * wi_z[i].abs() * pa / ((pa + pb) * a.pdf_light[i])
        } else {
            0.0
        }
    });
    out.nee = std::array::from_fn(|j| map(|i| rho[j][i] * a.l[j][i] * w_nee[i]));
    // Cosine-weighted sampling: the concentric map needs sin and cos on [−π/4, π/4] only.
    let ox = map(|i| 2.0 * a.u[0][i] - 1.0);
    let oy = map(|i| 2.0 * a.u[1][i] - 1.0);
    let first = map(|i| (ox[i].abs() > oy[i].abs()) as u32 as f32);
    let r = map(|i| if first[i] != 0.0 { ox[i] } else { oy[i] });
    let phi = map(|i| {
        let q = if first[i] != 0.0 {
            oy[i] / ox[i]
        } else {
            ox[i] / oy[i]
        };
        if q.is_finite() {
            std::f32::consts::FRAC_PI_4 * q
        } else {
            0.0
        }
    });
    let (sp, cp) = sin_cos_quarter(phi);
    // First case (cos φ, sin φ); second, θ = π/2 − φ: (sin φ, cos φ).
    let dx = map(|i| r[i] * if first[i] != 0.0 { cp[i] } else { sp[i] });
    let dy = map(|i| r[i] * if first[i] != 0.0 { sp[i] } else { cp[i] });
    let lz = map(|i| {
        let z = (1.0 - dx[i] * dx[i] - dy[i] * dy[i]).max(0.0).sqrt();
        if wo_z[i] < 0.0 {
            -z
        } else {
            z
        }
    });
    out.wi = V3 {
        x: map(|i| s.x[i] * dx[i] + t.x[i] * dy[i] + n.x[i] * lz[i]),
        y: map(|i| s.y[i] * dx[i] + t.y[i] * dy[i] + n.y[i] * lz[i]),
        z: map(|i| s.z[i] * dx[i] + t.z[i] * dy[i] + n.z[i] * lz[i]),
    };
    out.ok = std::array::from_fn(|i| a.hit[i] && wo_z[i] != 0.0 && lz[i] != 0.0);
    // f |cos| / p with p = |cos θi| / π: |wi · ns| π / |lz| (1 up to round-off) × R/π.
    let cos = dot(&out.wi, n);
    let w = map(|i| {
        if out.ok[i] {
            cos[i].abs() * std::f32::consts::PI / lz[i].abs()
        } else {
            0.0
        }
    });
    out.beta = rho.map(|r| map(|i| r[i] * w[i]));
}

/// A UsdPreviewSurface plastic's constants (`PreviewMaterial` with `PreviewLobes::Plastic`,
/// untextured, the specular workflow): the coat's GGX α, its albedo table (E(μ) at
/// μ = (j/15)², `CoatAlbedo::Table`), its average transmittance and the internal diffuse
/// Fresnel reflectance; the diffuse and F0 spectra are the material's tables.
#[derive(Clone, Copy)]
struct PlasticK {
    alpha: f32,
    albedo: [f32; 16],
    t_avg: f32,
    fdr: f32,
}

/// E(μ) of the coat albedo table (`CoatAlbedo::eval`).
#[inline(always)]
fn coat_albedo(t: &[f32; 16], mu: f32) -> f32 {
    let x = mu.abs().min(1.0).sqrt() * 15.0;
    let i = (x as usize).min(14);
    let a = x - i as f32;
    (1.0 - a) * t[i] + a * t[i + 1]
}

/// Λ(w) of an isotropic Trowbridge–Reitz distribution from cos² θ (PBR 4ed eq. 9.22).
#[inline(always)]
fn ggx_lambda(alpha: f32, cos2: f32) -> f32 {
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    if cos2 == 0.0 {
        f32::INFINITY
    } else {
        0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
    }
}

/// D(ωm) of an isotropic Trowbridge–Reitz distribution from cos² θm (PBR 4ed eq. 9.16).
#[inline(always)]
fn ggx_d(alpha: f32, cos2: f32) -> f32 {
    let cos4 = cos2 * cos2;
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    let e = tan2 / (alpha * alpha);
    let d = 1.0 / (std::f32::consts::PI * alpha * alpha * cos4 * (1.0 + e) * (1.0 + e));
    if cos4 < 1e-16 {
        0.0
    } else {
        d
    }
}

/// The plastic's f (coat + coupled diffuse) and pdf (coat VNDF and cosine, mixed by the
/// coat's selection probability pc) for one lane, both directions local and in the upper
/// hemisphere (`PlasticBxdf::f_upper`, `pdf_upper`), `tt` = T(μo) T(μi): f per wavelength is
/// F(ωo · ωm) D G / (4 cos θo cos θi) + diffuse · tt, returned as (D G / (4 cos cos),
/// Schlick's (1 − cos)⁵, tt) with the pdf; outside the upper hemisphere all 0.
#[inline(always)]
fn plastic_upper(alpha: f32, wo: Vec3, wi: Vec3, pc: f32, tt: f32) -> (f32, f32, f32, f32) {
    let upper = wi.z > 0.0 && wo.z > 0.0;
    let h = wo + wi;
    let len2 = h.length_squared();
    let ok = len2 > 0.0 && len2.is_finite();
    let wm = h * (1.0 / len2.sqrt());
    let (lo, li) = (
        ggx_lambda(alpha, wo.z * wo.z),
        ggx_lambda(alpha, wi.z * wi.z),
    );
    let d = ggx_d(alpha, wm.z * wm.z);
    let dg = d / (1.0 + lo + li) / (4.0 * wo.z * wi.z);
    let m = (1.0 - wo.dot(wm).abs().min(1.0)).max(0.0);
    let m5 = (m * m) * (m * m) * m;
    // The coat's pdf: D_visible(ωo, ωm) / (4 |ωo · ωm|) with ωm in the upper hemisphere.
    let dot = wo.dot(wm).abs();
    let pdf_coat = (1.0 / (1.0 + lo)) / wo.z * d * dot / (4.0 * dot);
    let pdf_cos = (1.0 - pc) * wi.z * INV_PI;
    // Selects, not branches, so that the loop over lanes vectorises.
    let (dg, m5, pdf) = if ok {
        (dg, m5, pc * pdf_coat + pdf_cos)
    } else {
        (0.0, 0.0, pdf_cos)
    };
    if upper {
        (dg, m5, tt, pdf)
    } else {
        (0.0, 0.0, 0.0, 0.0)
    }
}

/// The visible-normal sample of the coat's GGX (Heitz 2018; `TrowbridgeReitz::sample_wm`),
/// reflected about it (`sample_reflection`); the uniform disk's angle 2π u₁ is reduced to
/// [−π/4, π/4] by quadrant.
#[inline(always)]
fn ggx_sample(alpha: f32, wo: Vec3, u: [f32; 2]) -> Vec3 {
    let mut wh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    if wh.z < 0.0 {
        wh = -wh;
    }
    let t1 = if wh.z < 0.99999 {
        Vec3::new(-wh.y, wh.x, 0.0).normalize()
    } else {
        Vec3::X
    };
    let t2 = wh.cross(t1);
    let r = u[0].sqrt();
    let x = u[1] * 4.0;
    let q = (x + 0.5).floor();
    let (s, c) = sin_cos_quarter1((x - q) * std::f32::consts::FRAC_PI_2);
    // Rotated by q quarter turns: (c, s), (−s, c), (−c, −s), (s, −c).
    let k = q as i32 & 3;
    let (c, s) = if k & 1 == 0 { (c, s) } else { (-s, c) };
    let (c, s) = if k & 2 == 0 { (c, s) } else { (-c, -s) };
    let (px, py) = (r * c, r * s);
    let h = (1.0 - px * px).max(0.0).sqrt();
    let sw = 0.5 * (1.0 + wh.z);
    let py = (1.0 - sw) * h + sw * py;
    let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
    let nh = px * t1 + py * t2 + pz * wh;
    let wm = Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize();
    -wo + 2.0 * wo.dot(wm) * wm
}

/// The box's plastic for 8 lanes: the same arithmetic as `PreviewMaterial::plastic`,
/// `PlasticBxdf` and the `Bsdf` wrapper (frame, mirroring for ωo below the surface), NEE's
/// f, pdf and power-heuristic weight, and `sample_f` (coat or diffuse by uc < pc; both are
/// computed and one selected per lane, which is what lockstep costs on divergent branches).
/// In passes over the lanes: the per-material gathers, then the arithmetic.
#[inline(always)]
fn plastic_kernel(
    mats: &[PlasticK],
    tables: &[&[f32; DENSE_LEN]],
    f0s: &[&[f32; DENSE_LEN]],
    a: &ShadeIn,
    uc: &F,
    out: &mut ShadeOut,
) {
    // Gathers: the material's constants and its spectra at the lanes' wavelengths.
    let mk: [&PlasticK; W] = std::array::from_fn(|i| &mats[a.table[i]]);
    let alpha = map(|i| mk[i].alpha);
    let rho = gather_spectrum(tables, a);
    let f0 = gather_spectrum(f0s, a);
    let diffuse: [F; 4] = std::array::from_fn(|j| {
        map(|i| {
            let (fdr, t_avg) = (mk[i].fdr, mk[i].t_avg);
            let r = rho[j][i] * (1.0 - fdr) / (1.0 - rho[j][i] * fdr);
            if t_avg > 0.0 {
                r * (INV_PI / t_avg)
            } else {
                0.0
            }
        })
    });
    let diffuse_albedo = map(|i| {
        (0..4)
            .map(|j| rho[j][i] * (1.0 - mk[i].fdr) / (1.0 - rho[j][i] * mk[i].fdr))
            .sum::<f32>()
            / 4.0
    });
    // The shading frame; ωo and the light's ωi in it, mirrored above the surface.
    let (sf, tf) = frame_soa(&a.ns);
    let n = &a.ns;
    let wo = to_local(&sf, &tf, n, &a.wo);
    let flip: M = std::array::from_fn(|i| wo.z[i] < 0.0);
    let wo_u = mirror(&wo, &flip);
    let wl = mirror(&to_local(&sf, &tf, n, &a.wi_l), &flip);
    let e = map(|i| coat_albedo(&mk[i].albedo, wo_u.z[i]));
    let pc = map(|i| {
        let d = (1.0 - e[i]).max(0.0) * diffuse_albedo[i];
        if e[i] + d > 0.0 {
            e[i] / (e[i] + d)
        } else {
            1.0
        }
    });
    let t_o = map(|i| (1.0 - e[i]).max(0.0));
    // NEE.
    let t_l = map(|i| (1.0 - coat_albedo(&mk[i].albedo, wl.z[i])).max(0.0));
    let ev = upper_soa(&alpha, &wo_u, &wl, &pc, &t_o, &t_l);
    let w_nee = map(|i| {
        let (pa, pb) = (a.pdf_light[i] * a.pdf_light[i], ev.3[i] * ev.3[i]);
        let cos = (a.wi_l.x[i] * n.x[i] + a.wi_l.y[i] * n.y[i] + a.wi_l.z[i] * n.z[i]).abs();
        let live = a.hit[i] && a.light[i] && wo.z[i] != 0.0 && a.tr[i] > 0.0;
        if live && pa + pb > 0.0 {
            a.tr[i] * cos * pa / ((pa + pb) * a.pdf_light[i])
        } else {
            0.0
        }
    });
    out.nee = std::array::from_fn(|j| {
        map(|i| {
            let fr = f0[j][i] + (1.0 - f0[j][i]) * ev.1[i];
            (fr * ev.0[i] + diffuse[j][i] * ev.2[i]) * a.l[j][i] * w_nee[i]
        })
    });
    // BSDF sampling: the coat's visible normals or the cosine hemisphere, per lane.
    let mut wi = V3::default();
    for i in 0..W {
        let wo_i = lane(&wo_u, i);
        let u = [a.u[0][i], a.u[1][i]];
        let coat = ggx_sample(alpha[i], wo_i, u);
        let d = spectral_render::sampling::warp::concentric_disk(u);
        let cos = Vec3::new(d.x, d.y, (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt());
        set_lane(&mut wi, i, if uc[i] < pc[i] { coat } else { cos });
    }
    let t_i = map(|i| (1.0 - coat_albedo(&mk[i].albedo, wi.z[i])).max(0.0));
    let ev = upper_soa(&alpha, &wo_u, &wi, &pc, &t_o, &t_i);
    let wi_w = to_world(&sf, &tf, n, &mirror(&wi, &flip));
    let cos = dot(&wi_w, n);
    out.ok = std::array::from_fn(|i| {
        let dir = uc[i] >= pc[i] || wo_u.z[i] * wi.z[i] > 0.0;
        a.hit[i] && wo.z[i] != 0.0 && dir && ev.3[i] > 0.0 && ev.3[i].is_finite() && wi.z[i] != 0.0
    });
    let g = map(|i| {
        if out.ok[i] {
            cos[i].abs() / ev.3[i]
        } else {
            0.0
        }
    });
    out.beta = std::array::from_fn(|j| {
        map(|i| {
            let fr = f0[j][i] + (1.0 - f0[j][i]) * ev.1[i];
            (fr * ev.0[i] + diffuse[j][i] * ev.2[i]) * g[i]
        })
    });
    out.wi = wi_w;
}

/// A spectrum per lane at its 4 wavelengths from each lane's table, clamped to [0, 1].
#[inline(always)]
fn gather_spectrum(tables: &[&[f32; DENSE_LEN]], a: &ShadeIn) -> [F; 4] {
    std::array::from_fn(|j| {
        map(|i| {
            let t = tables[a.table[i]];
            let x = a.lambda[j][i] - LAMBDA_MIN;
            let k = (x as usize).min(DENSE_LEN - 2);
            let f = x - k as f32;
            (t[k] * (1.0 - f) + t[k + 1] * f).clamp(0.0, 1.0)
        })
    })
}

/// `Frame::from_normal` over the lanes: the tangents s, t.
#[inline(always)]
fn frame_soa(n: &V3) -> (V3, V3) {
    let sign = map(|i| 1.0f32.copysign(n.z[i]));
    let ka = map(|i| -1.0 / (sign[i] + n.z[i]));
    let kb = map(|i| n.x[i] * n.y[i] * ka[i]);
    let s = V3 {
        x: map(|i| 1.0 + sign[i] * n.x[i] * n.x[i] * ka[i]),
        y: map(|i| sign[i] * kb[i]),
        z: map(|i| -sign[i] * n.x[i]),
    };
    let t = V3 {
        x: kb,
        y: map(|i| sign[i] + n.y[i] * n.y[i] * ka[i]),
        z: map(|i| -n.y[i]),
    };
    (s, t)
}

#[inline(always)]
fn to_local(s: &V3, t: &V3, n: &V3, v: &V3) -> V3 {
    V3 {
        x: dot(v, s),
        y: dot(v, t),
        z: dot(v, n),
    }
}

#[inline(always)]
fn to_world(s: &V3, t: &V3, n: &V3, v: &V3) -> V3 {
    V3 {
        x: map(|i| s.x[i] * v.x[i] + t.x[i] * v.y[i] + n.x[i] * v.z[i]),
        y: map(|i| s.y[i] * v.x[i] + t.y[i] * v.y[i] + n.y[i] * v.z[i]),
        z: map(|i| s.z[i] * v.x[i] + t.z[i] * v.y[i] + n.z[i] * v.z[i]),
    }
}

#[inline(always)]
fn mirror(v: &V3, flip: &M) -> V3 {
    V3 {
        z: map(|i| if flip[i] { -v.z[i] } else { v.z[i] }),
        ..*v
    }
}

/// [`plastic_upper`] over the lanes, with the coat transmittances T(μo), T(μi) given.
#[inline(always)]
fn upper_soa(alpha: &F, wo: &V3, wi: &V3, pc: &F, t_o: &F, t_i: &F) -> (F, F, F, F) {
    let mut r = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
    for i in 0..W {
        let e = plastic_upper(alpha[i], lane(wo, i), lane(wi, i), pc[i], t_o[i] * t_i[i]);
        (r.0[i], r.1[i], r.2[i], r.3[i]) = e;
    }
    r
}

// The kernels compiled for the baseline target and for AVX2 + FMA. Each `stage_*` is one pass
// over all groups and is never inlined, so callgrind's inclusive counts separate the stages.

#[inline(never)]
fn stage_wavelengths_lockstep(u: &[F], lambda: &mut [[F; 4]], pdf: &mut [[F; 4]]) {
    for g in 0..u.len() {
        wavelengths_kernel(&u[g], &mut lambda[g], &mut pdf[g]);
    }
}

#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn stage_wavelengths_lockstep_avx2(u: &[F], lambda: &mut [[F; 4]], pdf: &mut [[F; 4]]) {
    for g in 0..u.len() {
        wavelengths_kernel(&u[g], &mut lambda[g], &mut pdf[g]);
    }
}

/// Per group: raster x, y in; origin, direction, t_max out.
type CamOut = (V3, V3, F);

#[inline(never)]
fn stage_camera_lockstep(k: &PinholeK, film: &[(F, F)], out: &mut [CamOut]) {
    for (f, o) in film.iter().zip(out.iter_mut()) {
        camera_kernel(k, &f.0, &f.1, &mut o.0, &mut o.1, &mut o.2);
    }
}

#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn stage_camera_lockstep_avx2(k: &PinholeK, film: &[(F, F)], out: &mut [CamOut]) {
    for (f, o) in film.iter().zip(out.iter_mut()) {
        camera_kernel(k, &f.0, &f.1, &mut o.0, &mut o.1, &mut o.2);
    }
}

#[inline(never)]
fn stage_shading_lockstep(t: &[&[f32; DENSE_LEN]], a: &[ShadeIn], out: &mut [ShadeOut]) {
    for (x, o) in a.iter().zip(out.iter_mut()) {
        shade_kernel(t, x, o);
    }
}

#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn stage_shading_lockstep_avx2(t: &[&[f32; DENSE_LEN]], a: &[ShadeIn], out: &mut [ShadeOut]) {
    for (x, o) in a.iter().zip(out.iter_mut()) {
        shade_kernel(t, x, o);
    }
}

/// The plastic's constants and tables for every material, and whether the material is an
/// untextured UsdPreviewSurface plastic in the specular workflow with a tabulated coat (the
/// others get placeholders: the plastic kernel runs only when no hit meets one).
type PlasticTables = (Vec<PlasticK>, Vec<DenseSpectrum>, Vec<bool>);

fn plastics(materials: &[Material]) -> PlasticTables {
    let (mut ks, mut f0s, mut known) = (Vec::new(), Vec::new(), Vec::new());
    for m in materials {
        let plastic = match m {
            Material::Preview(p) => {
                match (p.lobes, p.bsdf_is_textured(), &p.specular, p.base_albedo) {
                    (PreviewLobes::Plastic, false, Some(f0), CoatAlbedo::Table(albedo)) => Some((
                        PlasticK {
                            alpha: p.distrib.alpha_x,
                            albedo,
                            t_avg: p.base_t_avg,
                            fdr: p.base_fdr_internal,
                        },
                        DenseSpectrum::from_fn(|l| f0.eval(l)),
                    )),
                    _ => None,
                }
            }
            _ => None,
        };
        known.push(plastic.is_some());
        let (k, f0) = plastic.unwrap_or((
            PlasticK {
                alpha: 1.0,
                albedo: [0.0; 16],
                t_avg: 1.0,
                fdr: 0.0,
            },
            DenseSpectrum::constant(0.0),
        ));
        ks.push(k);
        f0s.push(f0);
    }
    (ks, f0s, known)
}

/// The plastic kernel's per-material data and each group's lobe-choice numbers.
type PlasticIn<'a> = (
    &'a [PlasticK],
    &'a [&'a [f32; DENSE_LEN]],
    &'a [&'a [f32; DENSE_LEN]],
    &'a [F],
);

#[inline(never)]
fn stage_plastic_lockstep(p: PlasticIn, a: &[ShadeIn], out: &mut [ShadeOut]) {
    for (g, (x, o)) in a.iter().zip(out.iter_mut()).enumerate() {
        plastic_kernel(p.0, p.1, p.2, x, &p.3[g], o);
    }
}

#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn stage_plastic_lockstep_avx2(p: PlasticIn, a: &[ShadeIn], out: &mut [ShadeOut]) {
    for (g, (x, o)) in a.iter().zip(out.iter_mut()).enumerate() {
        plastic_kernel(p.0, p.1, p.2, x, &p.3[g], o);
    }
}

// ---------------------------------------------------------------------------------------
// The scalar stages: today's code, one sample at a time.

/// A sample's random numbers, in the order the path tracer draws them for its first hit.
#[derive(Clone, Copy, Default)]
struct Us {
    wavelength: f32,
    film: [f32; 2],
    lens: [f32; 2],
    light: f32,
    light_2d: [f32; 2],
    bsdf: f32,
    bsdf_2d: [f32; 2],
}

#[inline(never)]
fn stage_sampler(width: u32, height: u32, us: &mut [Us]) {
    for y in 0..height {
        for x in 0..width {
            let pixel = u64::from(y * width + x);
            let mut s = Sampler::new(1, pixel, 0);
            us[pixel as usize] = Us {
                wavelength: s.get_1d(),
                film: s.get_2d(),
                lens: s.get_2d(),
                light: s.get_1d(),
                light_2d: s.get_2d(),
                bsdf: s.get_1d(),
                bsdf_2d: s.get_2d(),
            };
        }
    }
}

#[inline(never)]
fn stage_wavelengths_scalar(us: &[Us], out: &mut [SampledWavelengths]) {
    for (u, o) in us.iter().zip(out.iter_mut()) {
        *o = SampledWavelengths::sample_visible(u.wavelength);
    }
}

#[inline(never)]
fn stage_camera_scalar(scene: &Scene, width: u32, us: &[Us], out: &mut [(Ray, f32)]) {
    for (k, (u, o)) in us.iter().zip(out.iter_mut()).enumerate() {
        let (x, y) = (k as u32 % width, k as u32 / width);
        let film = [x as f32 + u.film[0], y as f32 + u.film[1]];
        *o = scene.camera.generate_ray(film, u.lens);
    }
}

#[inline(never)]
fn stage_intersect(scene: &Scene, rays: &[(Ray, f32)], out: &mut [Option<SurfaceHit>]) {
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        *o = match scene.intersect(&r.0, r.1) {
            Some(Hit::Surface(si)) => Some(si),
            _ => None,
        };
    }
}

/// The light sample of NEE at the first hit: the light chosen by power, a point on it, its
/// emission at the path's wavelengths, the pmf × pdf, and the shadow ray's answer (1 or 0).
#[derive(Clone, Copy)]
struct LightPick {
    ls: Option<LightLiSample>,
    pdf_light: f32,
    tr: f32,
}

#[inline(never)]
fn stage_light_sample(
    scene: &Scene,
    us: &[Us],
    hits: &[Option<SurfaceHit>],
    lambda: &[SampledWavelengths],
    out: &mut [LightPick],
) {
    for k in 0..us.len() {
        out[k] = LightPick {
            ls: None,
            pdf_light: 0.0,
            tr: 0.0,
        };
        let Some(si) = &hits[k] else { continue };
        let Some((light, pmf)) = scene.light_sampler.sample(us[k].light) else {
            continue;
        };
        let ctx = LightSampleContext { p: si.p, n: si.ng };
        let ls = scene.lights[light].sample_li(&ctx, us[k].light_2d, &lambda[k]);
        if let Some(ls) = ls.filter(|ls| !ls.l.is_black() && ls.pdf_w > 0.0) {
            out[k] = LightPick {
                ls: Some(ls),
                pdf_light: pmf * ls.pdf_w,
                tr: 1.0,
            };
        }
    }
}

/// The shadow ray of each light sample: its transmittance (1 or 0) into `tr`.
#[inline(never)]
fn stage_shadow_rays(
    scene: &Scene,
    hits: &[Option<SurfaceHit>],
    picks: &[LightPick],
    tr: &mut [f32],
) {
    for ((h, pick), tr) in hits.iter().zip(picks).zip(tr.iter_mut()) {
        *tr = 0.0;
        let (Some(si), Some(ls)) = (h, &pick.ls) else {
            continue;
        };
        *tr = 1.0;
        let (ray, t) = if ls.infinite {
            (spawn_ray(si.p, si.p_error, si.ng, ls.wi), f32::INFINITY)
        } else {
            spawn_ray_to_point(si.p, si.p_error, si.ng, ls.p_light)
        };
        if scene.occluded(&ray, t, None) {
            *tr = 0.0;
        }
    }
}

/// One sample's shading result: the NEE estimate, f cos / p of the sampled direction, and it.
#[derive(Clone, Copy, Default)]
struct Shaded {
    nee: SampledSpectrum,
    beta: SampledSpectrum,
    wi: Vec3,
}

/// A pass of [`shade_scalar`] with the scene's own materials.
#[inline(never)]
fn stage_shading_scalar_scene(materials: &[Material], x: ScalarIn, out: &mut [Shaded]) {
    shade_scalar(materials, x, out);
    // Keeps the two passes apart (identical bodies would be folded into one function).
    std::hint::black_box(1);
}

/// A pass of [`shade_scalar`] with the Lambertians.
#[inline(never)]
fn stage_shading_scalar_lambert(materials: &[Material], x: ScalarIn, out: &mut [Shaded]) {
    shade_scalar(materials, x, out);
    std::hint::black_box(2);
}

/// The per-sample inputs of the scalar shading stage: random numbers, camera rays, first
/// hits, wavelengths, light samples with their shadow rays' answers.
type ScalarIn<'a> = (
    &'a [Us],
    &'a [(Ray, f32)],
    &'a [Option<SurfaceHit>],
    &'a [SampledWavelengths],
    &'a [LightPick],
);

/// `integrator/path.rs`'s `scatter` at the first hit without its ray spawning and roulette:
/// the BSDF, NEE's f, pdf and MIS weight for the given light sample, and a BSDF sample.
#[inline(always)]
fn shade_scalar(materials: &[Material], x: ScalarIn, out: &mut [Shaded]) {
    let (us, rays, hits, lambda, picks) = x;
    let mode = TransportMode::Radiance;
    for k in 0..us.len() {
        out[k] = Shaded::default();
        let Some(si) = &hits[k] else { continue };
        let wo = -rays[k].0.d;
        let material = &materials[si.material as usize];
        let bsdf: Bsdf = material.bsdf(TexCoord::point(si.uv), si.ns, &lambda[k]);
        if let Some(ls) = &picks[k].ls {
            let f = bsdf.f(wo, ls.wi, mode) * ls.wi.dot(si.ns).abs();
            let tr = picks[k].tr;
            if !f.is_black() && tr > 0.0 {
                let pdf_light = picks[k].pdf_light;
                let w = power_heuristic(pdf_light, bsdf.pdf(wo, ls.wi, mode));
                out[k].nee = f * ls.l * (tr * w / pdf_light);
            }
        }
        let (uc, u) = (us[k].bsdf, us[k].bsdf_2d);
        if let Some(bs) = bsdf.sample_f(wo, uc, u, mode) {
            out[k].beta = bs.f * (bs.wi.dot(si.ns).abs() / bs.pdf_w);
            out[k].wi = bs.wi;
        }
    }
}

// ---------------------------------------------------------------------------------------
// Packing between the per-sample arrays and the groups (what a lockstep integrator would
// keep in SoA throughout; here the scalar ray queries and light samples sit in between).

fn pack_film(width: u32, us: &[Us]) -> Vec<(F, F)> {
    us.chunks(W)
        .enumerate()
        .map(|(g, c)| {
            let fx = map(|i| ((g * W + i) as u32 % width) as f32 + c[i].film[0]);
            let fy = map(|i| ((g * W + i) as u32 / width) as f32 + c[i].film[1]);
            (fx, fy)
        })
        .collect()
}

fn lane(v: &V3, i: usize) -> Vec3 {
    Vec3::new(v.x[i], v.y[i], v.z[i])
}

fn set_lane(v: &mut V3, i: usize, w: Vec3) {
    (v.x[i], v.y[i], v.z[i]) = (w.x, w.y, w.z);
}

/// The shading kernel's inputs for group `g` from the per-sample results.
fn pack_shade(
    g: usize,
    us: &[Us],
    rays: &[(Ray, f32)],
    hits: &[Option<SurfaceHit>],
    lambda: &[SampledWavelengths],
    picks: &[LightPick],
) -> ShadeIn {
    let mut a = ShadeIn {
        lambda: std::array::from_fn(|j| map(|i| lambda[g * W + i].lambda[j])),
        u: [
            map(|i| us[g * W + i].bsdf_2d[0]),
            map(|i| us[g * W + i].bsdf_2d[1]),
        ],
        ..ShadeIn::default()
    };
    for i in 0..W {
        let k = g * W + i;
        let Some(si) = &hits[k] else { continue };
        a.hit[i] = true;
        a.table[i] = si.material as usize;
        set_lane(&mut a.ns, i, si.ns);
        set_lane(&mut a.wo, i, -rays[k].0.d);
        if let Some(ls) = &picks[k].ls {
            a.light[i] = true;
            set_lane(&mut a.wi_l, i, ls.wi);
            for j in 0..4 {
                a.l[j][i] = ls.l[j];
            }
            a.pdf_light[i] = picks[k].pdf_light;
            a.tr[i] = picks[k].tr;
        }
    }
    a
}

/// The shading kernel's inputs for every group: the transposition from the scalar ray
/// queries' and light samples' results to SoA that a lockstep integrator would pay per bounce.
#[inline(never)]
fn stage_pack(x: ScalarIn, ins: &mut [ShadeIn]) {
    let (us, rays, hits, lam, picks) = x;
    for (g, a) in ins.iter_mut().enumerate() {
        *a = pack_shade(g, us, rays, hits, lam, picks);
    }
}

// ---------------------------------------------------------------------------------------

struct Args {
    stage: PathBuf,
    width: u32,
    height: u32,
    reps: usize,
    occupancy: bool,
}

fn args() -> Args {
    let mut a = Args {
        stage: PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/cornell-box.usda"
        )),
        width: 128,
        height: 128,
        reps: 9,
        occupancy: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(x) = it.next() {
        match x.as_str() {
            "--res" => {
                let v = it.next().unwrap_or_default();
                let (w, h) = v.split_once('x').unwrap_or(("128", "128"));
                (a.width, a.height) = (w.parse().unwrap_or(128), h.parse().unwrap_or(128));
            }
            "--reps" => a.reps = it.next().and_then(|v| v.parse().ok()).unwrap_or(9),
            "--occupancy" => a.occupancy = true,
            "--bench" => {}
            s if s.ends_with(".usda") || s.ends_with(".usdc") || s.ends_with(".usd") => {
                a.stage = PathBuf::from(s)
            }
            _ => {}
        }
    }
    a
}

/// The shortest wall time of `reps` runs of `f`, in ns per sample: on a shared machine the
/// least disturbed pass (the work is deterministic, so interference only adds time).
fn time(reps: usize, n: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e9 / n as f64
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[0]
}

fn main() {
    let a = args();
    let scene = match scene::load(&a.stage, Some((a.width, a.height))) {
        Ok(s) => s,
        Err(e) => refuse(&e.to_string()),
    };
    let (width, height) = (scene.camera.width, scene.camera.height);
    if a.occupancy {
        occupancy(&scene, width, height);
        return;
    }
    let stage = a.stage.display();
    if scene.camera.lens_radius > 0.0 {
        refuse(&format!(
            "{stage}: the prototype's camera kernel is a pinhole's"
        ));
    }
    let n = (width * height) as usize;
    if !n.is_multiple_of(W) {
        refuse(&format!(
            "{stage}: width × height must be a multiple of {W}"
        ));
    }
    println!(
        "{stage}: {width}×{height} = {n} samples, {} groups of {W}; one thread, fastest of {} passes; AVX2: {}",
        n / W,
        a.reps,
        has_avx2()
    );
    let (tables, lambert) = lambertians(&scene.materials);
    let sc = scalar_stages(&scene, &lambert, a.reps);
    let (lt, lo) = lockstep_stages(&scene, &sc, &tables, a.reps);
    report(&sc.t, &lt);
    let x: ScalarIn = (&sc.us, &sc.rays, &sc.hits, &sc.lam, &sc.picks);
    check(&sc.lam, &lo.lambda, (&sc.rays, &lo.cam));
    let mut shaded = vec![Shaded::default(); n];
    shade_scalar(&lambert, x, &mut shaded);
    let d = shading_diff(&shaded, &lo.lambert, &sc.hits);
    println!("  Lambertian shading: {d}");
    if let Some(out) = &lo.plastic {
        shade_scalar(&scene.materials, x, &mut shaded);
        let d = shading_diff(&shaded, out, &sc.hits);
        println!("  plastic shading: {d}");
    }
}

/// Ends the run with a one-line error.
fn refuse(message: &str) -> ! {
    eprintln!("{message}");
    std::process::exit(1);
}

/// The scalar stages' times, ns per sample.
#[derive(Clone, Copy)]
struct ScalarTimes {
    sampler: f64,
    wavelengths: f64,
    camera: f64,
    intersect: f64,
    light: f64,
    shadow: f64,
    shade_scene: f64,
    shade_lambert: f64,
}

/// The scalar stages' results (the lockstep stages start from the same ones) and times.
struct Scalar {
    us: Vec<Us>,
    lam: Vec<SampledWavelengths>,
    rays: Vec<(Ray, f32)>,
    hits: Vec<Option<SurfaceHit>>,
    picks: Vec<LightPick>,
    t: ScalarTimes,
}

/// Today's code, stage by stage, over every sample of the image.
fn scalar_stages(scene: &Scene, lambert: &[Material], reps: usize) -> Scalar {
    let (width, height) = (scene.camera.width, scene.camera.height);
    let n = (width * height) as usize;
    let mut us = vec![Us::default(); n];
    let sampler = time(reps, n, || stage_sampler(width, height, &mut us));
    let mut lam = vec![SampledWavelengths::sample_visible(0.0); n];
    let wavelengths = time(reps, n, || stage_wavelengths_scalar(&us, &mut lam));
    let mut rays = vec![(Ray::new(Vec3::ZERO, Vec3::Z), 0.0); n];
    let camera = time(reps, n, || {
        stage_camera_scalar(scene, width, &us, &mut rays)
    });
    let mut hits = vec![None; n];
    let intersect = time(reps, n, || stage_intersect(scene, &rays, &mut hits));
    let blank = LightPick {
        ls: None,
        pdf_light: 0.0,
        tr: 0.0,
    };
    let mut picks = vec![blank; n];
    let light = time(reps, n, || {
        stage_light_sample(scene, &us, &hits, &lam, &mut picks)
    });
    let mut tr = vec![0.0; n];
    let shadow = time(reps, n, || stage_shadow_rays(scene, &hits, &picks, &mut tr));
    picks.iter_mut().zip(&tr).for_each(|(p, t)| p.tr = *t);
    let mut shaded = vec![Shaded::default(); n];
    let x: ScalarIn = (&us, &rays, &hits, &lam, &picks);
    let shade_scene = time(reps, n, || {
        stage_shading_scalar_scene(&scene.materials, x, &mut shaded)
    });
    let shade_lambert = time(reps, n, || {
        stage_shading_scalar_lambert(lambert, x, &mut shaded)
    });
    let t = ScalarTimes {
        sampler,
        wavelengths,
        camera,
        intersect,
        light,
        shadow,
        shade_scene,
        shade_lambert,
    };
    Scalar {
        us,
        lam,
        rays,
        hits,
        picks,
        t,
    }
}

/// A lockstep stage's time with the baseline kernel and, on CPUs with AVX2 and FMA, with the
/// AVX2 kernel.
type Both = (f64, Option<f64>);

/// The lockstep stages' times, ns per sample (`plastic`: when the scene's hits are all on
/// plastics).
struct LockTimes {
    wavelengths: Both,
    camera: Both,
    lambert: Both,
    plastic: Option<Both>,
    pack: f64,
}

/// The lockstep stages' results, for the check.
struct LockOut {
    lambda: Vec<[F; 4]>,
    cam: Vec<CamOut>,
    lambert: Vec<ShadeOut>,
    plastic: Option<Vec<ShadeOut>>,
}

/// Times `f(false)` (the baseline kernel) and, when the CPU has AVX2 and FMA, `f(true)`
/// (which may then call the AVX2 kernel).
fn time_both(reps: usize, n: usize, mut f: impl FnMut(bool)) -> Both {
    let sse = time(reps, n, || f(false));
    (sse, has_avx2().then(|| time(reps, n, || f(true))))
}

/// The same stages over groups of 8, from the scalar stages' random numbers, rays, hits and
/// light samples (so that both shade the same samples).
fn lockstep_stages(
    scene: &Scene,
    sc: &Scalar,
    tables: &[DenseSpectrum],
    reps: usize,
) -> (LockTimes, LockOut) {
    let width = scene.camera.width;
    let n = sc.us.len();
    let groups = n / W;
    let us_w: Vec<F> = sc.us.chunks(W).map(|c| map(|i| c[i].wavelength)).collect();
    let mut lambda = vec![[[0.0; W]; 4]; groups];
    let mut pdf = vec![[[0.0; W]; 4]; groups];
    // SAFETY (every `unsafe` below): `time_both` asks for the AVX2 kernel only on CPUs with
    // AVX2 and FMA, the features those kernels are compiled for.
    let wavelengths = time_both(reps, n, |avx| {
        if avx {
            unsafe { stage_wavelengths_lockstep_avx2(&us_w, &mut lambda, &mut pdf) }
        } else {
            stage_wavelengths_lockstep(&us_w, &mut lambda, &mut pdf)
        }
    });
    let film = pack_film(width, &sc.us);
    let k = pinhole(scene);
    let mut cam = vec![(V3::default(), V3::default(), [0.0; W]); groups];
    let camera = time_both(reps, n, |avx| {
        if avx {
            unsafe { stage_camera_lockstep_avx2(&k, &film, &mut cam) }
        } else {
            stage_camera_lockstep(&k, &film, &mut cam)
        }
    });
    let x: ScalarIn = (&sc.us, &sc.rays, &sc.hits, &sc.lam, &sc.picks);
    let mut ins = vec![ShadeIn::default(); groups];
    let pack = time(reps, n, || stage_pack(x, &mut ins));
    let tables: Vec<&[f32; DENSE_LEN]> = tables.iter().map(|t| &*t.values).collect();
    let mut out = vec![ShadeOut::default(); groups];
    let lambert = time_both(reps, n, |avx| {
        if avx {
            unsafe { stage_shading_lockstep_avx2(&tables, &ins, &mut out) }
        } else {
            stage_shading_lockstep(&tables, &ins, &mut out)
        }
    });
    let lambert_out = out.clone();
    // The scene's own plastic, when every material a hit meets is one the kernel knows.
    let (ks, f0s, known) = plastics(&scene.materials);
    let plastic = sc
        .hits
        .iter()
        .flatten()
        .all(|h| known[h.material as usize])
        .then(|| {
            let f0: Vec<&[f32; DENSE_LEN]> = f0s.iter().map(|t| &*t.values).collect();
            let uc: Vec<F> = sc.us.chunks(W).map(|c| map(|i| c[i].bsdf)).collect();
            let p: PlasticIn = (&ks, &tables, &f0, &uc);
            time_both(reps, n, |avx| {
                if avx {
                    unsafe { stage_plastic_lockstep_avx2(p, &ins, &mut out) }
                } else {
                    stage_plastic_lockstep(p, &ins, &mut out)
                }
            })
        });
    let times = LockTimes {
        wavelengths,
        camera,
        lambert,
        plastic,
        pack,
    };
    let outs = LockOut {
        lambda,
        cam,
        lambert: lambert_out,
        plastic: plastic.map(|_| out),
    };
    (times, outs)
}

/// The faster of a stage's two kernels.
fn best((sse, avx): Both) -> f64 {
    avx.unwrap_or(sse).min(sse)
}

/// Prints the stages' times, the gains and the first hit's totals.
fn report(s: &ScalarTimes, l: &LockTimes) {
    let row = |name: &str, scalar: f64, (sse, avx): Both| {
        let avx_s = avx.map_or("-".to_string(), |v| format!("{v:.2}"));
        let sp = avx.map_or("-".to_string(), |v| format!("{:.2}×", scalar / v));
        println!(
            "{name:<34} {scalar:>9.2} {sse:>11.2} {avx_s:>11} {:>9.2}× {sp:>9}",
            scalar / sse
        );
    };
    println!(
        "\n{:<34} {:>9} {:>11} {:>11} {:>10} {:>9}",
        "stage (ns/sample)", "scalar", "lock SSE2", "lock AVX2", "SSE2 gain", "AVX2 gain"
    );
    row("wavelengths (4 per sample)", s.wavelengths, l.wavelengths);
    row("camera ray", s.camera, l.camera);
    row("shading, Lambertian", s.shade_lambert, l.lambert);
    match l.plastic {
        Some(p) => row("shading, the scene's plastic", s.shade_scene, p),
        None => println!("(a hit's material is not an untextured plastic: no plastic kernel)"),
    }
    println!(
        "{:<34} {:>9} {:>11.2}",
        "SoA packing of hits, light samples", "-", l.pack
    );
    println!("\nscalar in both (ns/sample):");
    println!("{:<34} {:>9.2}", "sampler (11 numbers)", s.sampler);
    println!("{:<34} {:>9.2}", "primary ray query", s.intersect);
    println!("{:<34} {:>9.2}", "light sample", s.light);
    println!("{:<34} {:>9.2}", "shadow ray query", s.shadow);
    println!(
        "{:<34} {:>9.2}",
        "shading, scene's BSDF (scalar)", s.shade_scene
    );
    let shared = s.sampler + s.intersect + s.light + s.shadow;
    let total_s = shared + s.wavelengths + s.camera + s.shade_lambert;
    let total_l = shared + best(l.wavelengths) + best(l.camera) + best(l.lambert) + l.pack;
    println!(
        "\nfirst hit, Lambertian walls: scalar {total_s:.1} ns/sample, lockstep {total_l:.1} ns/sample: {:.2}×",
        total_s / total_l
    );
    if let Some(p) = l.plastic {
        let ps = total_s - s.shade_lambert + s.shade_scene;
        let pl = total_l - best(l.lambert) + best(p);
        println!(
            "first hit, the scene's plastic: scalar {ps:.1} ns/sample, lockstep {pl:.1} ns/sample: {:.2}×",
            ps / pl
        );
    }
}

/// Largest relative differences of the NEE estimates and β, and of the sampled directions,
/// between the scalar and the lockstep shading.
fn shading_diff(shaded: &[Shaded], out: &[ShadeOut], hits: &[Option<SurfaceHit>]) -> String {
    let (mut dn, mut db, mut dw) = (0f32, 0f32, 0f32);
    let rel = |a: f32, b: f32| (a - b).abs() / b.abs().max(1e-6);
    let lit = shaded.iter().filter(|s| !s.nee.is_black()).count();
    for k in 0..shaded.len() {
        let (g, i) = (k / W, k % W);
        if hits[k].is_none() {
            continue;
        }
        for j in 0..4 {
            dn = dn.max(rel(out[g].nee[j][i], shaded[k].nee[j]));
            db = db.max(rel(out[g].beta[j][i], shaded[k].beta[j]));
        }
        if !shaded[k].beta.is_black() {
            dw = dw.max((shaded[k].wi - lane(&out[g].wi, i)).abs().max_element());
        }
    }
    format!("NEE {dn:.2e} rel ({lit} samples lit), β {db:.2e} rel, ωi {dw:.2e}")
}

/// Largest differences between the lockstep and the scalar results.
fn check(lam: &[SampledWavelengths], lam_w: &[[F; 4]], (rays, cam): (&[(Ray, f32)], &[CamOut])) {
    let (mut dl, mut dp, mut dd, mut dt) = (0f32, 0f32, 0f32, 0f32);
    let rel = |a: f32, b: f32| (a - b).abs() / b.abs().max(1e-6);
    for k in 0..lam.len() {
        let (g, i) = (k / W, k % W);
        for (l, lw) in lam[k].lambda.iter().zip(&lam_w[g]) {
            dl = dl.max((l - lw[i]).abs());
        }
        dd = dd.max((rays[k].0.d - lane(&cam[g].1, i)).abs().max_element());
        dp = dp.max((rays[k].0.o - lane(&cam[g].0, i)).abs().max_element());
        dt = dt.max(rel(cam[g].2[i], rays[k].1));
    }
    println!(
        "check, lockstep vs scalar: λ {dl:.2e} nm, ray o {dp:.2e}, d {dd:.2e}, t_max {dt:.2e} rel"
    );
}

fn has_avx2() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// The camera's constants for the pinhole kernel (`Camera::generate_ray`).
fn pinhole(scene: &Scene) -> PinholeK {
    let c = &scene.camera;
    let m = c.to_world;
    let row = |r: usize| [m.col(0)[r], m.col(1)[r], m.col(2)[r], m.col(3)[r]];
    PinholeK {
        m: [row(0), row(1), row(2)],
        sx: [2.0 * c.half_w / c.width as f32, -c.half_w],
        sy: [-2.0 * c.half_h / c.height as f32, c.half_h],
        near: c.clip_near,
        depth: c.clip_far - c.clip_near,
    }
}

/// Each material as a Lambertian of its diffuse reflectance (a UsdPreviewSurface's
/// `diffuseColor`, tabulated at 1 nm by the scene builder), and those tables for the lockstep
/// kernel, in the materials' order. Materials without a constant reflectance become white.
fn lambertians(materials: &[Material]) -> (Vec<DenseSpectrum>, Vec<Material>) {
    let mut tables = Vec::new();
    let mut lambert = Vec::new();
    for m in materials {
        let s = match m {
            Material::Preview(p) => p.diffuse.clone(),
            Material::Diffuse {
                reflectance: ColorInput::Constant(s),
            } => s.clone(),
            _ => Spectrum::Constant(1.0),
        };
        let table = DenseSpectrum::from_fn(|l| s.eval(l));
        lambert.push(Material::Diffuse {
            reflectance: ColorInput::Constant(Spectrum::Dense {
                data: Arc::new(table.clone()),
                scale: 1.0,
            }),
        });
        tables.push(table);
    }
    (tables, lambert)
}

// ---------------------------------------------------------------------------------------
// Lane occupancy per bounce.

/// The number of bounces the occupancy loop follows (the depth 7).
const MAX_DEPTH: usize = 7;

/// Which Russian roulette the occupancy loop plays.
#[derive(Clone, Copy, PartialEq)]
enum Roulette {
    /// pbrt-v4's, from the second bounce, q = 1 − max β (`integrator/path.rs`).
    Pbrt,
    /// Mitsuba 3's, from the fifth bounce, p = min(max β, 0.95) (docs/design.md §8,
    /// "Variance per sample").
    Mitsuba,
}

/// One path of the path tracer's loop (scene materials, `integrator/path.rs` without NEE,
/// which does not decide survival): the material of each vertex it scattered at, until it
/// escapes, meets an analytic light, has no BSDF sample or is ended by roulette.
fn walk(
    scene: &Scene,
    (ray, t_max): (Ray, f32),
    lambda: &SampledWavelengths,
    s: &mut Sampler,
    rr: Roulette,
) -> Vec<u32> {
    let mut mats = Vec::new();
    let (mut ray, mut t_max) = (ray, t_max);
    let mut beta = SampledSpectrum::ONE;
    for depth in 0..MAX_DEPTH {
        let Some(Hit::Surface(si)) = scene.intersect(&ray, t_max) else {
            break;
        };
        mats.push(si.material);
        let m = &scene.materials[si.material as usize];
        let bsdf = m.bsdf(TexCoord::point(si.uv), si.ns, lambda);
        s.get_1d();
        s.get_2d(); // the light sample's numbers
        let (uc, u) = (s.get_1d(), s.get_2d());
        let Some(bs) = bsdf.sample_f(-ray.d, uc, u, TransportMode::Radiance) else {
            break;
        };
        beta *= bs.f * (bs.wi.dot(si.ns).abs() / bs.pdf_w);
        ray = spawn_ray(si.p, si.p_error, si.ng, bs.wi);
        t_max = f32::INFINITY;
        let m = beta.max_value();
        if rr == Roulette::Pbrt && m < 1.0 && depth + 1 > 1 {
            let q = (1.0 - m).max(0.0);
            if s.get_1d() < q {
                break;
            }
            beta = beta / (1.0 - q);
        } else if rr == Roulette::Mitsuba && depth + 1 >= 5 {
            let p = m.min(0.95);
            if s.get_1d() >= p {
                break;
            }
            beta = beta / p;
        }
    }
    mats
}

/// Per bounce: lanes alive (scattering there) over groups of 8, and the masked loop's
/// utilisation (alive lanes / 8 × groups still running).
fn occupancy(scene: &Scene, width: u32, height: u32) {
    for rr in [Roulette::Pbrt, Roulette::Mitsuba] {
        println!(
            "\n== roulette: {}",
            match rr {
                Roulette::Pbrt => "pbrt-v4 (today's path tracer)",
                Roulette::Mitsuba => "Mitsuba 3 (from the 5th bounce)",
            }
        );
        occupancy_with(scene, width, height, rr);
    }
}

fn occupancy_with(scene: &Scene, width: u32, height: u32, rr: Roulette) {
    let camera = &scene.camera;
    let report = |name: &str, groups: &[Vec<Vec<u32>>]| {
        println!("\n{name}: {} groups of {W}", groups.len());
        println!(
            "bounce  alive/8  groups running  utilisation  lanes on the group's commonest material"
        );
        let (mut work, mut busy) = (0usize, 0usize);
        for b in 0..MAX_DEPTH {
            let (mut alive, mut running, mut same) = (0usize, 0usize, 0usize);
            for g in groups {
                let mats: Vec<u32> = g.iter().filter_map(|p| p.get(b).copied()).collect();
                alive += mats.len();
                if !mats.is_empty() {
                    running += 1;
                    let common = mats
                        .iter()
                        .map(|m| mats.iter().filter(|x| *x == m).count())
                        .max()
                        .unwrap_or(0);
                    same += common;
                }
            }
            work += alive;
            busy += running * W;
            println!(
                "{b:>6}  {:>7.2}  {:>14.3}  {:>11.3}  {:>8.3}",
                alive as f64 / groups.len() as f64,
                running as f64 / groups.len() as f64,
                alive as f64 / (running * W).max(1) as f64,
                same as f64 / alive.max(1) as f64
            );
        }
        println!(
            "all bounces: utilisation {:.3} (lane-steps with a live path / lane-steps run)",
            work as f64 / busy.max(1) as f64
        );
    };
    let path = |x: u32, y: u32, s: u64| {
        let mut smp = Sampler::new(1, u64::from(y * width + x), s);
        let lambda = SampledWavelengths::sample_visible(smp.get_1d());
        let (j, l) = (smp.get_2d(), smp.get_2d());
        let (ray, t) = camera.generate_ray([x as f32 + j[0], y as f32 + j[1]], l);
        walk(scene, (ray, t), &lambda, &mut smp, rr)
    };
    let blocks: Vec<Vec<Vec<u32>>> = (0..height / 2)
        .flat_map(|by| (0..width / 4).map(move |bx| (bx, by)))
        .map(|(bx, by)| {
            (0..W as u32)
                .map(|i| path(bx * 4 + i % 4, by * 2 + i / 4, 0))
                .collect()
        })
        .collect();
    report("4×2 pixel blocks, one sample each", &blocks);
    let pixels: Vec<Vec<Vec<u32>>> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| (0..W as u64).map(|s| path(x, y, s)).collect())
        .collect();
    report("8 samples of one pixel", &pixels);
}
