//! The public-corpus fixtures (`tests/data/corpus/`, README there): every stage loads, or
//! fails with the reason the corpus means it to (a missing layer, an invalid up axis, a
//! malformed attribute type), as one line naming the file.

use spectral_render::scene::{self, Machinery, ReadTime};
use std::path::{Path, PathBuf};

/// Stages that must not load, with a piece of the one-line error each must give.
const REFUSED: &[(&str, &str)] = &[
    ("payload/payload_invalid.usda", "unresolved Payload layer @"),
    (
        "references/reference_invalid.usda",
        "unresolved Reference layer @",
    ),
    (
        "references_prim/reference_prim_in_other_file.usda",
        "/World/Cube_invalid_reference: ",
    ),
    (
        "references_prim/reference_prim_in_same_file.usda",
        "/World/Cube_with_invalid_reference: ",
    ),
    (
        "subLayer/sublayer_invalid.usda",
        "unresolved sublayer @file_does_not_exist.usda@",
    ),
    ("upAxis/upAxis_X.usda", "got \"X\""),
    ("upAxis/upAxis_invalid.usda", "got \"invalid\""),
    (
        "normals_types/normalsTypes.usda",
        "/World/point3f: 'normals' is Vec3f, expected an array of 3-vectors",
    ),
    (
        "points_types/pointsTypes.usda",
        "'points' is IntVec, expected an array of 3-vectors",
    ),
];

fn stages(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            stages(&path, out);
        } else if path.extension().is_some_and(|e| e == "usda") {
            out.push(path);
        }
    }
}

#[test]
fn every_corpus_fixture_loads_or_is_refused_for_its_reason() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/corpus");
    let mut all = Vec::new();
    stages(&root, &mut all);
    all.sort();
    assert!(all.len() >= 90, "only {} stages", all.len());
    let mut refused = 0;
    for stage in &all {
        let name = stage.to_string_lossy();
        let loaded = scene::load_at(
            stage,
            Some((8, 8)),
            Machinery::default(),
            ReadTime::default(),
        );
        match REFUSED.iter().find(|(s, _)| name.ends_with(s)) {
            Some((_, reason)) => {
                let e = loaded
                    .err()
                    .unwrap_or_else(|| panic!("{name} loaded"))
                    .to_string();
                assert!(e.contains(reason) && !e.contains('\n'), "{name}: {e}");
                assert!(e.starts_with(&*name), "the error names the file: {e}");
                refused += 1;
            }
            None => {
                if let Err(e) = loaded {
                    panic!("{name}: {e}");
                }
            }
        }
    }
    assert_eq!(refused, REFUSED.len());
}

/// The stage's frame rates are read as authored (the EXR carries them).
#[test]
fn frame_rates_are_read_from_the_corpus_stages() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/corpus/usd-wg/test_assets/foundation/stage_configuration");
    let time = |file: &str| {
        scene::open(&dir.join(file))
            .and_then(|s| s.read(ReadTime::default()))
            .unwrap()
            .time
    };
    let t = time("framesPerSecond/framesPerSecond_24.usda");
    assert_eq!(t.frames_per_second, Some(24.0));
    assert_eq!(t.time_codes_per_second, None);
    assert_eq!(t.code, Some(0.0), "startTimeCode 0");
    let t = time("framesPerSecond_timeCodesPerSecond_mixed/24_48.usda");
    assert_eq!(
        (t.frames_per_second, t.time_codes_per_second),
        (Some(24.0), Some(48.0))
    );
    let t = time("upAxis/upAxis_Y.usda");
    assert_eq!((t.frames_per_second, t.time_codes_per_second), (None, None));
}
