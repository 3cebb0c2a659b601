//! The ray classes of `../shared/limit` (the Embree 3 traversal ceiling on this machine) traced
//! through our BVH, for a direct Mrays/s comparison with its "mode 1" (one ray per call)
//! figures. The scene is read from the same OBJ subset (`v`, `f`, and the `#@camera` /
//! `#@emitter` directives, see `../shared/limit/README.md`) and the rays are made the same way:
//!
//! - primary: pinhole camera, one jittered sample per pixel per pass, 8×8 pixel tiles;
//! - diffuse: one per primary hit, from the hit offset by eps along the normal facing the
//!   camera, cosine-distributed around it;
//! - shadow: one per primary hit, towards a uniform point on the emitter, stopping eps short
//!   (skipped when the point is behind the surface or the emitter faces away).
//!
//! eps = 1e-4 × the scene's bounding-box diagonal. Rays are generated before timing; closest
//! hits (`Bvh::intersect`) for primary and diffuse rays, any hit (`Bvh::occluded`) for shadow
//! rays, on one thread (median of 5 runs; also per CPU-second of that thread, which stays
//! comparable with Embree's Mrays/s ÷ cpu% when other processes share the cores) and on all
//! rayon threads. The header gives, for each builder of the binary BVH (obvhs's PLOC and our
//! binned SAH), the build time, the BVH's memory (nodes, triangles) and its SAH: the expected
//! 8-wide node tests and triangle tests of a ray meeting the root box (`Bvh::sah_cost`). The
//! rays are traced through `Bvh::build`'s tree, or the one `--builder=ploc|sah` names.
//!
//! `cargo bench --bench limit_rays [-- SCENE.obj [SPP]] [--builder=ploc|sah]`; default
//! `../shared/limit/scenes/cbox.obj` at 4 spp (256×256 from the camera line: 262,144 primary
//! rays).

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use spectral_render::accel::bvh::{Builder, Bvh, TraversalCount};
use spectral_render::geometry::Ray;
use spectral_render::sampling::Sampler;

/// A scene of the limit benchmark: triangles, camera, emitter.
struct LimitScene {
    triangles: Vec<[Vec3; 3]>,
    /// Position, view direction, up, horizontal field of view (degrees), width, height.
    camera: (Vec3, Vec3, Vec3, f32, usize, usize),
    /// Parallelogram `o + s e1 + t e2`, emitting along `e1 × e2`.
    emitter: Option<(Vec3, Vec3, Vec3)>,
}

fn parse_obj(text: &str) -> LimitScene {
    let (mut verts, mut triangles) = (Vec::new(), Vec::new());
    let (mut camera, mut emitter) = (None, None);
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let tag = words.next().unwrap_or("");
        let nums: Vec<f32> = words.clone().filter_map(|w| w.parse().ok()).collect();
        let v3 = |k: usize| Vec3::new(nums[k], nums[k + 1], nums[k + 2]);
        match tag {
            "v" => verts.push(v3(0)),
            "f" => {
                let index = |w: &str| {
                    let i: i64 = w.split('/').next().unwrap().parse().unwrap();
                    (if i < 0 { verts.len() as i64 + i } else { i - 1 }) as usize
                };
                let f: Vec<usize> = words.map(index).collect();
                for k in 1..f.len() - 1 {
                    triangles.push([verts[f[0]], verts[f[k]], verts[f[k + 1]]]);
                }
            }
            "#@camera" => {
                camera = Some((
                    v3(0),
                    v3(3),
                    v3(6),
                    nums[9],
                    nums[10] as usize,
                    nums[11] as usize,
                ))
            }
            "#@emitter" => emitter = Some((v3(0), v3(3), v3(6))),
            _ => {}
        }
    }
    let camera = camera.expect("the scene file has no #@camera line");
    LimitScene {
        triangles,
        camera,
        emitter,
    }
}

/// Pass-major, 8×8 pixel tiles, scanlines inside a tile.
fn primary_rays(scene: &LimitScene, spp: usize, rng: &mut Sampler) -> Vec<Ray> {
    let (pos, f, up, hfov, w, h) = scene.camera;
    let (f, tx) = (f.normalize(), (0.5 * hfov).to_radians().tan());
    let (r, ty) = (f.cross(up).normalize(), tx * h as f32 / w as f32);
    let u = r.cross(f);
    let mut rays = Vec::with_capacity(w * h * spp);
    for _ in 0..spp {
        for (y0, x0) in (0..h)
            .step_by(8)
            .flat_map(|y| (0..w).step_by(8).map(move |x| (y, x)))
        {
            for (y, x) in
                (y0..(y0 + 8).min(h)).flat_map(|y| (x0..(x0 + 8).min(w)).map(move |x| (y, x)))
            {
                let sx = (2.0 * (x as f32 + rng.get_1d()) / w as f32 - 1.0) * tx;
                let sy = (1.0 - 2.0 * (y as f32 + rng.get_1d()) / h as f32) * ty;
                rays.push(Ray::new(pos, (f + r * sx + u * sy).normalize()));
            }
        }
    }
    rays
}

/// Diffuse and shadow rays from the primary hits.
fn secondary_rays(
    scene: &LimitScene,
    bvh: &Bvh,
    primary: &[Ray],
    rng: &mut Sampler,
) -> (Vec<Ray>, Vec<(Ray, f32)>) {
    let (lo, hi) = bvh.bounds();
    let eps = 1e-4 * (hi - lo).length();
    let (mut diffuse, mut shadow) = (Vec::new(), Vec::new());
    for ray in primary {
        let Some(hit) = bvh.intersect(ray, f32::INFINITY) else {
            continue;
        };
        let [p0, p1, p2] = scene.triangles[hit.prim as usize];
        let mut n = (p1 - p0).cross(p2 - p0).normalize();
        if n.dot(ray.d) > 0.0 {
            n = -n;
        }
        let org = ray.at(hit.hit.t) + n * eps;
        let (u1, u2) = (rng.get_1d(), rng.get_1d());
        let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
        let (t, b) = n.any_orthonormal_pair();
        let w = (t * (u1.sqrt() * c) + b * (u1.sqrt() * s) + n * (1.0 - u1).max(0.0).sqrt())
            .normalize();
        diffuse.push(Ray::new(org, w));
        if let Some((o, e1, e2)) = scene.emitter {
            let v = o + e1 * rng.get_1d() + e2 * rng.get_1d() - org;
            let (dist, w) = (v.length(), v.normalize());
            if w.dot(n) > 0.0 && w.dot(e1.cross(e2)) < 0.0 {
                shadow.push((Ray::new(org, w), dist * (1.0 - 1e-4) - eps));
            }
        }
    }
    (diffuse, shadow)
}

/// Seconds this thread has run on a CPU (Linux `/proc/thread-self/schedstat`, nanoseconds);
/// None elsewhere.
fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = stat.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// One class's figures: Mrays/s on one thread (median of 5 runs), the same per CPU-second of
/// that thread (what the figure would be on an idle core; NaN without schedstat), on all rayon
/// threads, and the hit fraction.
struct Throughput {
    one: f64,
    one_cpu: f64,
    all: f64,
    hit: f64,
}

fn throughput<T: Sync>(rays: &[T], f: impl Fn(&T) -> bool + Sync) -> Throughput {
    let (mut wall, mut cpu): (Vec<f64>, Vec<f64>) = (0..5)
        .map(|_| {
            let (start, cpu_start) = (Instant::now(), thread_cpu_seconds());
            std::hint::black_box(rays.iter().filter(|r| f(r)).count());
            let cpu = thread_cpu_seconds()
                .zip(cpu_start)
                .map_or(f64::NAN, |(b, a)| b - a);
            let mrays = rays.len() as f64 / 1e6;
            (mrays / start.elapsed().as_secs_f64(), mrays / cpu)
        })
        .unzip();
    wall.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    let start = Instant::now();
    let hits = rays.par_iter().filter(|r| f(r)).count();
    Throughput {
        one: wall[2],
        one_cpu: cpu[2],
        all: rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6,
        hit: hits as f64 / rays.len() as f64,
    }
}

/// Builds the scene's BVH with `builder` and prints its build time, memory and SAH.
fn build(scene: &LimitScene, builder: Builder) -> Bvh {
    let start = Instant::now();
    let bvh = Bvh::build_with(&scene.triangles, builder);
    let build = start.elapsed().as_secs_f64();
    let (nodes, triangles) = bvh.memory_bytes();
    let mib = |bytes: usize| bytes as f64 / (1024.0 * 1024.0);
    let sah = bvh.sah_cost();
    println!(
        "{:>5}: build {build:.3} s, memory {:.3} MiB (nodes {:.3}, triangles {:.3}), \
         SAH {:.2} node + {:.2} triangle tests per ray",
        format!("{builder:?}"),
        mib(nodes + triangles),
        mib(nodes),
        mib(triangles),
        sah.nodes,
        sah.triangles
    );
    bvh
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let path = args.first().cloned().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../shared/limit/scenes/cbox.obj"
        )
        .to_string()
    });
    let spp = args.get(1).map_or(4, |s| s.parse().expect("SPP"));
    let Ok(text) = std::fs::read_to_string(&path) else {
        println!("limit_rays: no scene at {path}; pass an OBJ of ../shared/limit as argument");
        return;
    };
    let scene = parse_obj(&text);
    println!("{path}: {} triangles", scene.triangles.len());
    let chosen = std::env::args()
        .find_map(|a| match a.as_str() {
            "--builder=ploc" => Some(Builder::Ploc),
            "--builder=sah" => Some(Builder::Sah),
            _ => None,
        })
        .unwrap_or(Builder::DEFAULT);
    // Both trees are built (and their figures printed) before the chosen one is kept.
    let trees = [Builder::Ploc, Builder::Sah].map(|builder| (builder, build(&scene, builder)));
    let bvh = trees
        .into_iter()
        .find_map(|(builder, bvh)| (builder == chosen).then_some(bvh))
        .expect("the chosen builder is one of the two");
    let mut rng = Sampler::new(7, 0, 0);
    let primary = primary_rays(&scene, spp, &mut rng);
    let (diffuse, shadow) = secondary_rays(&scene, &bvh, &primary, &mut rng);
    println!("rays traced through the {chosen:?} tree");
    println!(
        "{:>8} {:>9} {:>7} {:>14} {:>14} {:>14} {:>10} {:>10}",
        "class",
        "rays",
        "hit %",
        "Mrays/s 1 thr",
        "per CPU-s",
        "all threads",
        "nodes/ray",
        "tris/ray"
    );
    let any = |(r, t): &(Ray, f32)| trace_shadow(&bvh, r, *t);
    // The tests per ray, counted in a pass of their own (the timed queries count nothing).
    let count = TraversalCount::default();
    let rows = [
        (
            "primary",
            primary.len(),
            throughput(&primary, |r| trace_primary(&bvh, r)),
            {
                primary.iter().for_each(|r| {
                    bvh.count_closest(r, f32::INFINITY, &count);
                });
                per_ray(&count, primary.len())
            },
        ),
        (
            "diffuse",
            diffuse.len(),
            throughput(&diffuse, |r| trace_diffuse(&bvh, r)),
            {
                diffuse.iter().for_each(|r| {
                    bvh.count_closest(r, f32::INFINITY, &count);
                });
                per_ray(&count, diffuse.len())
            },
        ),
        ("shadow", shadow.len(), throughput(&shadow, any), {
            shadow.iter().for_each(|(r, t)| {
                bvh.count_any(r, *t, &count);
            });
            per_ray(&count, shadow.len())
        }),
    ];
    for (class, n, t, (nodes, triangles)) in rows {
        println!(
            "{class:>8} {n:>9} {:>7.1} {:>14.2} {:>14.2} {:>14.2} {nodes:>10.2} {triangles:>10.2}",
            100.0 * t.hit,
            t.one,
            t.one_cpu,
            t.all
        );
    }
}

/// The timed queries of each class, out of line so that callgrind's inclusive counts of
/// `limit_rays::trace_primary`, `trace_diffuse` and `trace_shadow` are exactly the queries of
/// that class's timed passes: 6 calls per ray (5 runs on one thread, one on all threads).
/// The `black_box`ed tag keeps the linker from folding the two identical closest-hit copies.
#[inline(never)]
fn trace_primary(bvh: &Bvh, ray: &Ray) -> bool {
    std::hint::black_box(1u8);
    bvh.intersect(ray, f32::INFINITY).is_some()
}

/// The diffuse rays' queries (see [`trace_primary`]).
#[inline(never)]
fn trace_diffuse(bvh: &Bvh, ray: &Ray) -> bool {
    std::hint::black_box(2u8);
    bvh.intersect(ray, f32::INFINITY).is_some()
}

/// The shadow rays' queries (see [`trace_primary`]).
#[inline(never)]
fn trace_shadow(bvh: &Bvh, ray: &Ray, t_max: f32) -> bool {
    bvh.occluded(ray, t_max)
}

/// The counts per ray of `rays` rays (nodes, triangles), and `count` reset.
fn per_ray(count: &TraversalCount, rays: usize) -> (f64, f64) {
    let per = |c: &std::cell::Cell<u64>| c.take() as f64 / rays.max(1) as f64;
    (per(&count.nodes), per(&count.triangles))
}
