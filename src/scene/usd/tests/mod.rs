//! Tests of the USD reader: small inline `.usda` fixtures written to a temporary directory,
//! plus the Cornell box in `tests/data/usd/`.

mod errors;
mod geometry;
mod lights;
mod materials;
mod robust;
mod stage;
mod time;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::desc::{MeshDesc, SceneDescription};
use crate::error::Error;

/// Layer metadata for a Y-up stage in metres.
const METRES_Y_UP: &str = "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n";

/// A fresh directory for one test.
fn temp_dir() -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("spectral-render-usd-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Writes `text` as `name` in a fresh directory and returns its path.
fn write_stage(name: &str, text: &str) -> PathBuf {
    let path = temp_dir().join(name);
    std::fs::write(&path, text).expect("write stage");
    path
}

/// Loads a stage made of `METRES_Y_UP` and `body`.
fn load_body(body: &str) -> SceneDescription {
    load_text(&format!("{METRES_Y_UP}{body}"))
}

/// Loads a complete `.usda` text.
fn load_text(text: &str) -> SceneDescription {
    let path = write_stage("stage.usda", text);
    match super::load(&path) {
        Ok(desc) => desc,
        Err(e) => panic!("load failed: {e}"),
    }
}

/// Loads a stage made of `METRES_Y_UP` and `body`, expecting an error.
fn load_body_err(body: &str) -> Error {
    let path = write_stage("bad_stage.usda", &format!("{METRES_Y_UP}{body}"));
    let err = super::load(&path).expect_err("the stage should not load");
    assert_one_line(&err, "bad_stage.usda");
    err
}

/// The error's Display is one line and names the file.
fn assert_one_line(err: &Error, file_name: &str) {
    let text = err.to_string();
    assert!(!text.contains('\n'), "multi-line error: {text:?}");
    assert!(
        text.contains(file_name),
        "error does not name the file: {text}"
    );
}

/// The mesh with `prim_path`.
fn mesh<'a>(desc: &'a SceneDescription, prim_path: &str) -> &'a MeshDesc {
    let found = desc.meshes.iter().find(|m| m.prim_path == prim_path);
    found.unwrap_or_else(|| panic!("no mesh {prim_path}; have {:?}", paths(desc)))
}

/// The prim paths of all meshes.
fn paths(desc: &SceneDescription) -> Vec<&str> {
    desc.meshes.iter().map(|m| m.prim_path.as_str()).collect()
}

/// The geometric normal of triangle `t`.
fn face_normal(mesh: &MeshDesc, t: usize) -> glam::Vec3 {
    let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
    (b - a).cross(c - a).normalize()
}

/// `a` and `b` agree within `eps` component-wise.
fn assert_close(a: glam::Vec3, b: glam::Vec3, eps: f32) {
    assert!((a - b).abs().max_element() <= eps, "{a:?} != {b:?}");
}

/// A warning containing all of `parts` was issued.
fn assert_warned(desc: &SceneDescription, parts: &[&str]) {
    let found = desc
        .warnings
        .iter()
        .any(|w| parts.iter().all(|p| w.contains(p)));
    assert!(found, "no warning with {parts:?} in {:#?}", desc.warnings);
}

/// The Cornell box fixture.
fn cbox_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usd/cbox.usda")
}
