//! Unused machinery never runs, and forcing it back on changes only time (issue 11): each
//! piece the scene builder leaves out (`scene::machinery`) is forced on in a scene that does
//! not need it, and the image must stay the same — bit for bit where the maths is the same
//! arithmetic (the light-selection table of a single light, the per-vertex dispersion check),
//! and to float round-off where the pruned model computes the same function differently
//! (UsdPreviewSurface lobes of weight 0): there every pixel agrees to 1e-5 but a handful where
//! a path took another lobe, and those pass a z-test.

mod common;
use common::*;
use spectral_render::light::LightSampler;
use spectral_render::material::preview::PreviewLobes;
use spectral_render::material::Material;
use spectral_render::scene::{self, Machinery, Scene};
use spectral_render::session::{self, Control, ImageSession, PassStats, RenderOptions};
use spectral_render::Integrator;

fn load(path: &std::path::Path, machinery: Machinery) -> Scene {
    scene::load_with(path, Some((32, 32)), machinery).unwrap_or_else(|e| panic!("{e}"))
}

/// The image (XYZ) and the per-pixel variance of its luminance.
fn render(scene: &Scene, integrator: Integrator, spp: u32) -> (Vec<[f32; 3]>, Vec<f64>) {
    let opts = RenderOptions {
        spp: Some(spp),
        seed: 3,
        integrator,
        ..Default::default()
    };
    let mut s = ImageSession::new(scene, &opts).unwrap();
    let mut variance = Vec::new();
    session::run(&mut s, &mut |p: &PassStats| {
        variance = p.variance.clone();
        Control::Continue
    });
    let out = s.output();
    assert_finite(&out);
    (out.xyz, variance)
}

fn lobes(scene: &Scene) -> Vec<PreviewLobes> {
    scene
        .materials
        .iter()
        .filter_map(|m| match m {
            Material::Preview(p) => Some(p.lobes),
            _ => None,
        })
        .collect()
}

/// UsdPreviewSurfaces whose clearcoat and metal have weight 0: the specular workflow with
/// `specularColor` 0 keeps its coat (F90 = 1) and becomes the plastic; the metallic workflow
/// with `ior` 1 has a coat that reflects nothing and becomes a Lambertian; one with metal and
/// clearcoat keeps everything.
fn preview_stage() -> String {
    let preview = |name: &str, inputs: &str| {
        material(
            name,
            "UsdPreviewSurface",
            &format!("        color3f inputs:diffuseColor = (0.7, 0.5, 0.3)\n{inputs}"),
        )
    };
    let looks = preview(
        "Spec0",
        "        int inputs:useSpecularWorkflow = 1\n        color3f inputs:specularColor = (0, 0, 0)\n        float inputs:roughness = 1\n",
    ) + &preview("Ior1", "        float inputs:ior = 1\n        float inputs:roughness = 0.4\n")
        + &preview(
            "Coated",
            "        float inputs:metallic = 0.3\n        float inputs:clearcoat = 0.5\n",
        );
    let mut s = header();
    s += &camera(2.5, 0.6, 0.0);
    s += &looks_scope(&looks);
    s += "def SphereLight \"Lamp\"\n{\n    float inputs:radius = 0.2\n    float inputs:intensity = 300\n    double3 xformOp:translate = (0, 0.6, 1)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}\n\n";
    for (i, (name, x)) in [("Spec0", -0.7), ("Ior1", 0.0), ("Coated", 0.7)]
        .iter()
        .enumerate()
    {
        let api = BINDING_API;
        let (pts, faces) = cube(0.3);
        let pts: Vec<_> = pts
            .iter()
            .map(|p| *p + glam::DVec3::new(*x, 0.0, 0.0))
            .collect();
        s += &mesh(&format!("Box{i}"), api, &pts, &faces, &binding(name));
    }
    let floor = [
        glam::DVec3::new(-2.0, -0.3, -2.0),
        glam::DVec3::new(-2.0, -0.3, 2.0),
        glam::DVec3::new(2.0, -0.3, 2.0),
        glam::DVec3::new(2.0, -0.3, -2.0),
    ];
    s += &mesh("Floor", BINDING_API, &floor, &one_face(4), &binding("Ior1"));
    s
}

#[test]
fn zero_weight_lobes_are_pruned_and_forcing_them_changes_only_round_off() {
    let dir = temp_dir("prune-lobes");
    let path = write(&dir, "preview.usda", &preview_stage());
    let (pruned, full) = (
        load(&path, Machinery::default()),
        load(&path, Machinery::parse("lobes").unwrap()),
    );
    use PreviewLobes::*;
    assert_eq!(lobes(&pruned), [Plastic, Lambert, Full]);
    assert_eq!(lobes(&full), [Full, Full, Full]);
    for integrator in [Integrator::Path, Integrator::from_name("bdpt").unwrap()] {
        let (a, va) = render(&pruned, integrator, 32);
        let (b, vb) = render(&full, integrator, 32);
        let (mut off, mut worst_z) = (0, 0.0f64);
        let (mut sum_a, mut sum_b) = (0.0f64, 0.0f64);
        for i in 0..a.len() {
            let (ya, yb) = (f64::from(a[i][1]), f64::from(b[i][1]));
            sum_a += ya;
            sum_b += yb;
            if (ya - yb).abs() <= 1e-5 * ya.abs().max(yb.abs()) + 1e-9 {
                continue;
            }
            off += 1;
            let z = (ya - yb).abs() / (va[i] + vb[i]).sqrt();
            worst_z = worst_z.max(z);
        }
        eprintln!(
            "{}: {off} of {} pixels beyond 1e-5, worst z {worst_z:.2}; means {sum_a} {sum_b}",
            integrator.name(),
            a.len()
        );
        assert!(off * 1000 <= a.len(), "{off} pixels differ");
        assert!(worst_z < 4.0, "z = {worst_z}");
        assert!((sum_a / sum_b - 1.0).abs() < 1e-5, "{sum_a} vs {sum_b}");
    }
}

#[test]
fn one_light_needs_no_table_and_no_dispersion_needs_no_check_bit_for_bit() {
    let path = cbox_path();
    let plain = load(&path, Machinery::default());
    assert!(
        matches!(plain.light_sampler, LightSampler::Power(_)),
        "the mesh light of cbox.usda is two triangles: a table"
    );
    let dir = temp_dir("prune-single");
    let single = write(&dir, "single.usda", &preview_stage());
    let plain = load(&single, Machinery::default());
    assert!(matches!(plain.light_sampler, LightSampler::Single));
    assert!(!plain.dispersive);
    let forced = load(&single, Machinery::parse("light-table,dispersion").unwrap());
    assert!(matches!(forced.light_sampler, LightSampler::Power(_)));
    assert!(forced.dispersive);
    for integrator in [
        Integrator::Path,
        Integrator::Light,
        Integrator::from_name("bdpt").unwrap(),
    ] {
        let (a, _) = render(&plain, integrator, 4);
        let (b, _) = render(&forced, integrator, 4);
        assert!(a == b, "{}: the images differ", integrator.name());
    }
}

#[test]
fn the_hidden_flag_forces_machinery_and_names_the_choices() {
    let dir = temp_dir("prune-cli");
    write(&dir, "s.usda", &preview_stage());
    let args = ["s.usda", "--spp", "1", "--resolution", "4x4"];
    let o = spectral_render(&[&args[..], &["--force-machinery", "all"]].concat(), &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = spectral_render(&[&args[..], &["--force-machinery", "bvh"]].concat(), &dir);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.starts_with("error: ") && e.contains("light-table") && e.lines().count() == 1,
        "{e}"
    );
    let help = stdout(&spectral_render(&["--help"], &dir));
    assert!(!help.contains("force-machinery"), "the flag is hidden");
}
