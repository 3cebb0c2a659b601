//! A material's spectra that do not depend on the hit — its untextured reflectances, a
//! conductor's η and k, a dielectric's IOR, a Schlick F0, a plastic's diffuse base —
//! sampled at one wavelength tuple ([`MaterialSpectra`]), and a per-thread cache of them
//! ([`SpectraCache`]) so that they are sampled once per material and tuple rather than at
//! every hit (issue 18, "hot-path hygiene"; docs/design.md §8 "Material spectra per
//! wavelength tuple").
//!
//! [`Material::bsdf`] is [`Material::bsdf_with`] of [`Material::constant_spectra`]: the
//! cached and the uncached BSDF are one computation, bit for bit. A path tracer's sample
//! reuses an entry whenever its path meets a material again; VCM's samples of one iteration
//! share their tuple, so an iteration fills each material's entry once per thread.
//!
//! **Shared entries.** Materials whose constant spectra are equal at every tuple — the same
//! model with bit-identical inputs ([`same_spectra`]), such as the Cornell box's six white
//! surfaces, bound to six material prims — share one entry, so a path that meets the floor
//! and then the ceiling samples the white once. The cache maps materials to entries when it
//! first sees a scene, against at most [`MAX_SHARED`] distinct entries (beyond them every
//! further material gets an entry of its own, and so does every material of a scene with more
//! than [`MAX_SHARING_MATERIALS`]).
//!
//! **Invalidation.** Each entry carries the generation it was filled in; [`SpectraCache::begin`]
//! starts a new generation when the tuple (its wavelengths, bit for bit) or the scene's
//! materials change, so a hit compares one integer, not four floats. Every walk that builds
//! BSDFs calls `begin` with its wavelengths first (a sample's subpaths share one tuple:
//! terminating the secondary wavelengths changes their pdfs, never the wavelengths, and the
//! constants depend on the wavelengths alone). Memory: at most one 56-byte entry and a 4-byte
//! index per material, allocated when a scene is first seen; nothing per sample.

use super::{ColorInput, Material, PlasticMaterial, PreviewMaterial};
use crate::bxdf::{Bsdf, PlasticBase};
use crate::spectral::{SampledSpectrum, SampledWavelengths, N_LAMBDA};
use crate::texture::TexCoord;
use glam::Vec3;

/// A material's hit-independent spectra at one wavelength tuple. Which fields a model fills
/// is [`Material::constant_spectra`]'s table; the others are zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialSpectra {
    /// A constant reflectance ρ clamped to [0, 1] (diffuse, Oren–Nayar, plastic,
    /// UsdPreviewSurface `diffuseColor`); a conductor's η; a dielectric's IOR (the hero's
    /// in lane 0 for a solid, every lane's for a thin one).
    pub s0: SampledSpectrum,
    /// A conductor's k; UsdPreviewSurface's Schlick F0 (`specularColor`, specular workflow).
    pub s1: SampledSpectrum,
    /// The diffuse base of a plastic whose ρ and coat roughness are both constant.
    pub base: PlasticBase,
}

/// One material's entry: its spectra and the generation they belong to.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    generation: u32,
    spectra: MaterialSpectra,
}

/// Per-thread [`MaterialSpectra`] of every material of a scene at the current wavelength
/// tuple, filled lazily (the module header). Plain data; reused from sample to sample.
#[derive(Clone, Debug, Default)]
pub struct SpectraCache {
    /// The current generation; 0 only while `entries` is empty.
    generation: u32,
    /// The current tuple's wavelengths, as bits.
    lambda: [u32; N_LAMBDA],
    /// The address of the scene's material array the entries are for.
    materials: usize,
    /// Each material's entry.
    slots: Vec<u32>,
    entries: Vec<Entry>,
}

/// The distinct entries a new material is compared with when a scene is first seen.
pub const MAX_SHARED: usize = 64;
/// Scenes with more materials give every material an entry of its own, so that mapping a
/// scene (once per thread, and per task of VCM's store fill) stays O(materials).
pub const MAX_SHARING_MATERIALS: usize = 256;

impl SpectraCache {
    /// Bytes per entry (at most one per material, besides its 4-byte index).
    pub const BYTES_PER_MATERIAL: usize = std::mem::size_of::<Entry>();

    /// Makes `lambda` the current tuple for the scene whose materials are `materials`: a new
    /// generation when either changed (the entries of the old one are then stale), nothing
    /// otherwise.
    #[inline]
    pub fn begin(&mut self, materials: &[Material], lambda: &SampledWavelengths) {
        let bits = lambda.lambda.map(f32::to_bits);
        let id = materials.as_ptr() as usize;
        let same_scene = id == self.materials && materials.len() == self.slots.len();
        if bits == self.lambda && same_scene && self.generation != 0 {
            return;
        }
        if !same_scene {
            self.new_scene(materials);
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            // Wrapped after 2³² tuples: every entry is stale.
            self.entries.iter_mut().for_each(|e| e.generation = 0);
            self.generation = 1;
        }
        self.lambda = bits;
        self.materials = id;
    }

    /// Maps the materials of a scene not seen before to entries, sharing an entry between
    /// materials of equal constant spectra ([`same_spectra`]).
    #[cold]
    fn new_scene(&mut self, materials: &[Material]) {
        // (a material, its entry) for the first MAX_SHARED distinct ones.
        let mut shared: Vec<(usize, u32)> = Vec::new();
        let limit = if materials.len() <= MAX_SHARING_MATERIALS {
            MAX_SHARED
        } else {
            0
        };
        let mut entries = 0u32;
        self.slots.clear();
        for (i, m) in materials.iter().enumerate() {
            let equal = shared.iter().find(|(r, _)| same_spectra(&materials[*r], m));
            let slot = match equal {
                Some(&(_, slot)) => slot,
                None => {
                    entries += 1;
                    if shared.len() < limit {
                        shared.push((i, entries - 1));
                    }
                    entries - 1
                }
            };
            self.slots.push(slot);
        }
        self.entries.clear();
        self.entries.resize(entries as usize, Entry::default());
        self.generation = 0;
        self.materials = materials.as_ptr() as usize;
    }

    /// The spectra of `material`, the scene's material number `index`, at the current tuple
    /// `lambda` (the one of the last [`Self::begin`]): sampled now if this generation has not
    /// yet met the material (or one sharing its entry); None when `begin` never saw the
    /// scene.
    #[inline]
    pub fn get(
        &mut self,
        material: &Material,
        index: usize,
        lambda: &SampledWavelengths,
    ) -> Option<&MaterialSpectra> {
        debug_assert_eq!(self.lambda, lambda.lambda.map(f32::to_bits));
        let generation = self.generation;
        let slot = self.slots.get(index).map_or(usize::MAX, |&s| s as usize);
        let e = self.entries.get_mut(slot)?;
        if e.generation != generation {
            e.spectra = material.constant_spectra(lambda);
            e.generation = generation;
        }
        Some(&e.spectra)
    }

    /// [`Material::bsdf`] of `material` (the scene's material `index`) through the cache.
    #[inline]
    pub fn bsdf(
        &mut self,
        material: &Material,
        index: usize,
        tc: TexCoord,
        ns: Vec3,
        lambda: &SampledWavelengths,
    ) -> Bsdf {
        match self.get(material, index, lambda) {
            Some(c) => material.bsdf_with(tc, ns, lambda, c),
            None => material.bsdf(tc, ns, lambda),
        }
    }

    /// Entries filled in the current generation (for tests).
    #[cfg(test)]
    fn entries(&self) -> usize {
        self.entries.len()
    }

    /// Entries filled in the current generation (for tests).
    #[cfg(test)]
    fn filled(&self) -> usize {
        let g = self.generation;
        self.entries.iter().filter(|e| e.generation == g).count()
    }
}

/// True when `a` and `b` have the same [`Material::constant_spectra`] at every wavelength
/// tuple: the same model with bit-identical inputs to them. Conservative: false for
/// representations it does not compare (RGB illuminants: `Spectrum::same_bits`).
pub fn same_spectra(a: &Material, b: &Material) -> bool {
    use Material as M;
    match (a, b) {
        (M::Diffuse { reflectance: x }, M::Diffuse { reflectance: y })
        | (M::OrenNayar { reflectance: x, .. }, M::OrenNayar { reflectance: y, .. }) => {
            same_input(x, y)
        }
        (M::Conductor { eta: e, k, .. }, M::Conductor { eta: f, k: l, .. }) => {
            e.same_bits(f) && k.same_bits(l)
        }
        (M::Dielectric { ior: x, .. }, M::Dielectric { ior: y, .. })
        | (M::ThinDielectric { ior: x }, M::ThinDielectric { ior: y }) => {
            bits(&x.b) == bits(&y.b) && bits(&x.c) == bits(&y.c)
        }
        (M::Plastic(p), M::Plastic(q)) => same_plastic(p, q),
        (M::Preview(p), M::Preview(q)) => same_preview(p, q),
        _ => false,
    }
}

fn same_plastic(p: &PlasticMaterial, q: &PlasticMaterial) -> bool {
    same_input(&p.reflectance, &q.reflectance)
        && p.roughness.is_none() == q.roughness.is_none()
        && p.fdr_internal.to_bits() == q.fdr_internal.to_bits()
        && p.t_avg.to_bits() == q.t_avg.to_bits()
}

fn same_preview(p: &PreviewMaterial, q: &PreviewMaterial) -> bool {
    let (tp, tq) = (&p.textures, &q.textures);
    let diffuse = match (&tp.diffuse, &tq.diffuse) {
        (None, None) => p.diffuse.same_bits(&q.diffuse),
        (Some(_), Some(_)) => true,
        _ => false,
    };
    let specular = match ((&p.specular, &tp.specular), (&q.specular, &tq.specular)) {
        ((Some(s), None), (Some(t), None)) => s.same_bits(t),
        ((Some(_), None), _) | (_, (Some(_), None)) => false,
        _ => true,
    };
    diffuse
        && specular
        && p.lobes == q.lobes
        && tp.base_coats.is_none() == tq.base_coats.is_none()
        && p.base_fdr_internal.to_bits() == q.base_fdr_internal.to_bits()
        && p.base_t_avg.to_bits() == q.base_t_avg.to_bits()
}

/// Both constants of bit-identical spectra, or both textures (no constant).
fn same_input(x: &ColorInput, y: &ColorInput) -> bool {
    match (x, y) {
        (ColorInput::Constant(s), ColorInput::Constant(t)) => s.same_bits(t),
        (ColorInput::Texture(_), ColorInput::Texture(_)) => true,
        _ => false,
    }
}

fn bits(v: &[f32; 3]) -> [u32; 3] {
    v.map(f32::to_bits)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bxdf::TransportMode;
    use crate::spectral::Spectrum;

    /// The bits of f(ωo, ωi) of material `i`'s BSDF through `cache` and without it, at one
    /// fixed pair of directions.
    fn cached_and_uncached(
        cache: &mut SpectraCache,
        ms: &[Material],
        i: usize,
        l: &SampledWavelengths,
    ) -> ([u32; N_LAMBDA], [u32; N_LAMBDA]) {
        let (wo, wi) = (Vec3::new(0.3, 0.1, 0.9).normalize(), Vec3::Z);
        let tc = TexCoord::point(glam::Vec2::ZERO);
        let f = |b: Bsdf| b.f(wo, wi, TransportMode::Radiance).0.map(f32::to_bits);
        (
            f(cache.bsdf(&ms[i], i, tc, Vec3::Z, l)),
            f(ms[i].bsdf(tc, Vec3::Z, l)),
        )
    }

    fn lambda(u: f32) -> SampledWavelengths {
        SampledWavelengths::sample_visible(u)
    }

    fn materials() -> Vec<Material> {
        let red = Spectrum::Sigmoid(crate::spectral::uplift::reflectance([0.7, 0.1, 0.05]));
        vec![
            Material::Diffuse {
                reflectance: ColorInput::Constant(red.clone().tabulated()),
            },
            Material::Plastic(PlasticMaterial::new(red, 1.5, 0.2)),
        ]
    }

    /// The BSDF through the cache is the uncached one, bit for bit, at every tuple and in any
    /// order of hits, and a changed tuple is never served stale values.
    #[test]
    fn cached_bsdfs_are_the_uncached_ones() {
        let ms = materials();
        let mut cache = SpectraCache::default();
        for (k, u) in [0.1f32, 0.1, 0.7, 0.35, 0.7].into_iter().enumerate() {
            let l = lambda(u);
            cache.begin(&ms, &l);
            for i in [1usize, 0, 1, 0] {
                let (fa, fb) = cached_and_uncached(&mut cache, &ms, i, &l);
                assert_eq!(fa, fb, "{k} {i}");
            }
            assert_eq!(cache.filled(), 2);
        }
    }

    /// Materials of equal constant spectra share an entry; any difference in a model's
    /// inputs keeps them apart.
    #[test]
    fn equal_materials_share_an_entry() {
        let red = Spectrum::Sigmoid(crate::spectral::uplift::reflectance([0.7, 0.1, 0.05]));
        let white = Spectrum::Sigmoid(crate::spectral::uplift::reflectance([0.8, 0.7, 0.7]));
        let diffuse = |s: &Spectrum| Material::Diffuse {
            reflectance: ColorInput::Constant(s.clone().tabulated()),
        };
        let plastic =
            |s: &Spectrum, eta| Material::Plastic(PlasticMaterial::new(s.clone(), eta, 0.2));
        let ms = vec![
            diffuse(&white),
            diffuse(&red),
            diffuse(&white),
            plastic(&white, 1.5),
            plastic(&white, 1.5),
            plastic(&white, 1.4),
            Material::Conductor {
                eta: Spectrum::Constant(0.2),
                k: Spectrum::Constant(3.0),
                distrib: crate::bxdf::TrowbridgeReitz::isotropic(0.1),
                roughness: None,
            },
        ];
        let mut cache = SpectraCache::default();
        let l = lambda(0.4);
        cache.begin(&ms, &l);
        assert_eq!(cache.slots, vec![0, 1, 0, 2, 2, 3, 4]);
        assert_eq!(cache.entries(), 5);
        assert!(same_spectra(&ms[0], &ms[2]) && !same_spectra(&ms[0], &ms[1]));
        assert!(!same_spectra(&ms[0], &ms[3]) && !same_spectra(&ms[4], &ms[5]));
        for i in [3usize, 0, 4, 2, 5, 1, 6, 0] {
            let (fa, fb) = cached_and_uncached(&mut cache, &ms, i, &l);
            assert_eq!(fa, fb, "{i}");
        }
        assert_eq!(cache.filled(), 5);
        // Beyond MAX_SHARED distinct materials every further one has an entry of its own.
        let many: Vec<Material> = (0..MAX_SHARED + 3)
            .map(|k| diffuse(&Spectrum::Constant(k as f32 / 100.0)))
            .chain([diffuse(&Spectrum::Constant(0.0))])
            .collect();
        cache.begin(&many, &l);
        assert_eq!(cache.entries(), MAX_SHARED + 3);
        assert_eq!(cache.slots[MAX_SHARED + 3], 0);
        // A scene of more than MAX_SHARING_MATERIALS materials shares nothing.
        let large: Vec<Material> = (0..=MAX_SHARING_MATERIALS)
            .map(|_| diffuse(&white))
            .collect();
        cache.begin(&large, &l);
        assert_eq!(cache.entries(), large.len());
    }

    #[test]
    fn generations_follow_the_tuple_and_the_scene() {
        let (ms, other) = (materials(), materials());
        let mut cache = SpectraCache::default();
        let tc = TexCoord::point(glam::Vec2::ZERO);
        // Before any begin: uncached, nothing filled.
        let l = lambda(0.2);
        assert_eq!(cache.get(&ms[0], 0, &l), None);
        assert_eq!(cache.entries.len(), 0);
        cache.begin(&ms, &l);
        let g = cache.generation;
        cache.bsdf(&ms[0], 0, tc, Vec3::Z, &l);
        cache.begin(&ms, &l);
        assert_eq!((cache.generation, cache.filled()), (g, 1));
        // Terminating the secondary wavelengths keeps the tuple.
        let mut t = l;
        t.terminate_secondary();
        cache.begin(&ms, &t);
        assert_eq!((cache.generation, cache.filled()), (g, 1));
        let l2 = lambda(0.6);
        cache.begin(&ms, &l2);
        assert_eq!((cache.generation, cache.filled()), (g + 1, 0));
        assert_eq!(
            cache.get(&ms[0], 0, &l2),
            Some(&ms[0].constant_spectra(&l2))
        );
        cache.begin(&other, &l2);
        assert_eq!(cache.filled(), 0);
        // The generation wraps without serving stale entries.
        cache.generation = u32::MAX;
        cache.get(&other[1], 1, &l2);
        cache.begin(&other, &l);
        assert_eq!((cache.generation, cache.filled()), (1, 0));
        assert_eq!(
            cache.get(&other[1], 1, &l),
            Some(&other[1].constant_spectra(&l))
        );
    }
}
