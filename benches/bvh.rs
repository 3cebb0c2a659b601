//! BVH benchmark: build time and traversal throughput (Mrays/s) on random and structured
//! triangle sets. A plain program (`harness = false`): `cargo bench --bench bvh [-- --quick]`.
//!
//! Rays: "primary" = a pinhole camera's rays over the scene (coherent), "random" = origins
//! uniform in the scene bounds and directions uniform on the sphere (incoherent). Closest-hit
//! (`intersect`) and any-hit (`occluded`) are timed on one thread and on all rayon threads.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use spectral_render::accel::bvh::Bvh;
use spectral_render::geometry::Ray;
use spectral_render::sampling::warp::uniform_sphere;
use spectral_render::sampling::Sampler;

/// Benchmark inputs from the renderer's own generator.
struct Rng(Sampler<'static>);

impl Rng {
    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.0.get_1d(), self.0.get_1d(), self.0.get_1d())
    }

    fn unit_vector(&mut self) -> Vec3 {
        uniform_sphere(self.0.get_2d())
    }
}

/// Small random triangles in the unit cube.
fn random_soup(n: usize, rng: &mut Rng) -> Vec<[Vec3; 3]> {
    let size = 2.0 / (n as f32).cbrt();
    (0..n)
        .map(|_| {
            let c = rng.vec3();
            [0, 1, 2].map(|_| c + (rng.vec3() - 0.5) * size)
        })
        .collect()
}

/// A height field (a structured, connected mesh) of about `n` triangles over the unit square.
fn terrain(n: usize) -> Vec<[Vec3; 3]> {
    let k = ((n / 2) as f32).sqrt() as usize;
    let at = |i: usize, j: usize| {
        let (x, z) = (i as f32 / k as f32, j as f32 / k as f32);
        let h = 0.1 * (x * 17.0).sin() * (z * 13.0).cos() + 0.03 * (x * 71.0 + z * 53.0).sin();
        Vec3::new(x, h, z)
    };
    let mut tris = Vec::with_capacity(2 * k * k);
    for j in 0..k {
        for i in 0..k {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    tris
}

fn primary_rays(bounds: (Vec3, Vec3), width: usize, height: usize) -> Vec<Ray> {
    let (lo, hi) = bounds;
    let center = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let eye = center + Vec3::new(0.3, 0.8, 0.5).normalize() * radius * 1.6;
    let forward = (center - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let half = (25.0f32).to_radians().tan();
    let mut rays = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let sx =
                (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * half * width as f32 / height as f32;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * half;
            rays.push(Ray::new(eye, (forward + right * sx + up * sy).normalize()));
        }
    }
    rays
}

fn random_rays(bounds: (Vec3, Vec3), n: usize, rng: &mut Rng) -> Vec<Ray> {
    let (lo, hi) = bounds;
    (0..n)
        .map(|_| Ray::new(lo + (hi - lo) * rng.vec3(), rng.unit_vector()))
        .collect()
}

/// Mrays/s of `f` over `rays`, single-threaded and on all rayon threads; plus the hit count.
fn throughput(rays: &[Ray], f: impl Fn(&Ray) -> bool + Sync) -> (f64, f64, usize) {
    let start = Instant::now();
    let hits = rays.iter().filter(|r| f(r)).count();
    let single = rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6;
    let start = Instant::now();
    let hits_par = rays.par_iter().filter(|r| f(r)).count();
    let parallel = rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6;
    assert_eq!(hits, hits_par);
    (single, parallel, hits)
}

fn bench_scene(name: &str, tris: &[[Vec3; 3]], n_rays: usize, rng: &mut Rng) {
    let start = Instant::now();
    let bvh = Bvh::build(tris);
    let build = start.elapsed().as_secs_f64();
    println!(
        "{name}: {} triangles, build {:.3} s ({:.2} Mtris/s)",
        tris.len(),
        build,
        tris.len() as f64 / build / 1e6
    );
    let width = (n_rays as f64).sqrt() as usize;
    let sets = [
        ("primary", primary_rays(bvh.bounds(), width, width)),
        ("random", random_rays(bvh.bounds(), n_rays, rng)),
    ];
    for (kind, rays) in &sets {
        let (c1, cn, hits) = throughput(rays, |r| bvh.intersect(r, f32::INFINITY).is_some());
        let (o1, on, _) = throughput(rays, |r| bvh.occluded(r, f32::INFINITY));
        println!(
            "  {kind:>7} rays ({:>3.0}% hit): closest {c1:6.2} Mrays/s (1 thread) {cn:6.2} ({} threads) | any-hit {o1:6.2} / {on:6.2}",
            100.0 * hits as f64 / rays.len() as f64,
            rayon::current_num_threads(),
        );
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (n, n_rays) = if quick {
        (50_000, 100_000)
    } else {
        (300_000, 1_000_000)
    };
    let mut rng = Rng(Sampler::new(42, 0, 0));
    bench_scene("random soup", &random_soup(n, &mut rng), n_rays, &mut rng);
    bench_scene("terrain", &terrain(n), n_rays, &mut rng);
    if !quick {
        let big = terrain(1_000_000);
        let start = Instant::now();
        let bvh = Bvh::build(&big);
        println!(
            "terrain: {} triangles, build {:.3} s",
            bvh.triangle_count(),
            start.elapsed().as_secs_f64()
        );
    }
}
