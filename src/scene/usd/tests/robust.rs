//! Hostile stages (issue 13): each is a clear one-line error or a named warning, never a
//! panic, an abort, a stack overflow or a silent default. These tests run on the test
//! harness's threads (2 MiB stacks), so the depth limits are checked there too.

use super::*;

/// A triangle on the floor, a bulb and a camera: a stage that renders.
const SCENE: &str = "def Mesh \"Floor\" {
    point3f[] points = [(-1, 0, -1), (1, 0, -1), (0, 0, 1)]
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 2, 1]
}
def SphereLight \"Bulb\" {
    float inputs:radius = 0.05
    double3 xformOp:translate = (0, 1, 0)
    uniform token[] xformOpOrder = [\"xformOp:translate\"]
}
";

/// The error names `prim` (when given) and contains `reason`.
fn assert_error(err: &Error, prim: Option<&str>, reason: &str) {
    assert_eq!(err.prim.as_deref(), prim, "{err}");
    assert!(err.to_string().contains(reason), "{err}");
}

#[test]
fn an_inherits_arc_into_a_cycle_is_an_error() {
    let err = load_body_err(
        "def Xform \"A\" ( inherits = </B> ) {}\nclass \"B\" ( inherits = </C> ) {}\nclass \"C\" ( inherits = </B> ) {}\n",
    );
    assert_error(
        &err,
        None,
        "inherits/specializes arcs form a cycle through </B>",
    );
    let err = load_body_err("def Xform \"A\" ( inherits = </A> ) {}\n");
    assert_error(&err, None, "cycle through </A>");
}

#[test]
fn a_long_chain_of_inherits_is_an_error() {
    let mut body = String::from("def Xform \"A\" ( inherits = </K0> ) {}\n");
    for k in 0..100 {
        body += &format!("class \"K{k}\" ( inherits = </K{}> ) {{}}\n", k + 1);
    }
    let err = load_body_err(&body);
    assert_error(&err, None, "a chain of 101 inherits/specializes arcs");
}

/// `n` nested Xforms around a light.
fn nested(n: usize) -> String {
    let mut body = String::new();
    for i in 0..n {
        body += &format!("def Xform \"P{i}\" {{\n");
    }
    body += "def SphereLight \"L\" { float inputs:radius = 0.1 }\n";
    body + &"}\n".repeat(n)
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    for n in [2_000, 10_000] {
        let err = load_body_err(&nested(n));
        assert_error(&err, None, "brackets nested more than 320 levels deep");
    }
}

#[test]
fn nesting_within_the_limit_loads_quickly() {
    // A guard against a hang (parsing that grows exponentially with the depth would take
    // hours at 250 levels), not a speed target: the bound is wide enough for a machine loaded
    // many times over (8 s seen at a load of 13 on 2 cores; well under 1 s unloaded).
    let start = std::time::Instant::now();
    let desc = load_body(&nested(250));
    assert_eq!(desc.lights.len(), 1);
    assert!(
        start.elapsed().as_secs_f64() < 120.0,
        "{:?}",
        start.elapsed()
    );
}

#[test]
fn a_reference_to_a_missing_prim_is_an_error() {
    let err = load_body_err("def Xform \"A\" ( references = </Missing> ) {}\n");
    assert_error(
        &err,
        Some("/A"),
        "references </Missing>, which does not exist",
    );

    let dir = temp_dir();
    std::fs::write(
        dir.join("part.usda"),
        format!("{METRES_Y_UP}def Xform \"Part\" {{}}\n"),
    )
    .unwrap();
    let stage = |body: &str| {
        let path = dir.join("main.usda");
        std::fs::write(&path, format!("{METRES_Y_UP}{body}")).unwrap();
        super::super::load(&path)
    };
    let ok = stage("def Xform \"A\" ( references = @part.usda@</Part> ) {}\n");
    assert!(ok.is_ok(), "{:?}", ok.err());
    let err = stage("def Xform \"A\" ( references = @part.usda@</Nope> ) {}\n").unwrap_err();
    assert_error(
        &err,
        Some("/A"),
        "references </Nope> in @part.usda@, which does not exist",
    );
    let err = stage("def Xform \"A\" ( references = @part.usda@ ) {}\n").unwrap_err();
    assert_error(
        &err,
        Some("/A"),
        "without a prim path, and it has no defaultPrim",
    );
}

#[test]
fn a_short_tuple_is_an_error() {
    let err = load_body_err(&SCENE.replace("(0, 0, 1)", "(0, 0)"));
    assert_error(
        &err,
        None,
        "line 7: a tuple of 2 values in a point3f value, which needs 3",
    );
}

#[test]
fn nan_transforms_are_errors_naming_the_prim() {
    let camera = "def Camera \"Cam\" {\n    double3 xformOp:translate = (nan, 0, 3)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}\n";
    let err = load_body_err(&format!("{SCENE}{camera}"));
    assert_error(&err, Some("/Cam"), "'xformOp:translate' is not finite");
    let light = SCENE.replace(
        "double3 xformOp:translate = (0, 1, 0)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]",
        "float3 xformOp:rotateXYZ = (0, nan, 0)\n    uniform token[] xformOpOrder = [\"xformOp:rotateXYZ\"]",
    );
    let err = load_body_err(&light);
    assert_error(&err, Some("/Bulb"), "'xformOp:rotateXYZ' is not finite");
    let huge = SCENE.replace(
        "double3 xformOp:translate = (0, 1, 0)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]",
        "double3 xformOp:scale = (1e200, 1e200, 1e200)\n    double3 xformOp:scale:b = (1e200, 1, 1)\n    uniform token[] xformOpOrder = [\"xformOp:scale\", \"xformOp:scale:b\"]",
    );
    let err = load_body_err(&huge);
    assert_error(&err, Some("/Bulb"), "the composed transform overflows");
}

#[test]
fn a_thin_lens_needs_a_focus_distance() {
    for focus in [
        "",
        "    float focusDistance = 0\n",
        "    float focusDistance = -2\n",
    ] {
        let camera = format!("def Camera \"Cam\" {{\n    float fStop = 2.8\n{focus}}}\n");
        let err = load_body_err(&format!("{SCENE}{camera}"));
        assert_error(&err, Some("/Cam"), "needs focusDistance > 0");
    }
    let camera = "def Camera \"Cam\" {\n    float fStop = 2.8\n    float focusDistance = 3\n}\n";
    assert_eq!(load_body(&format!("{SCENE}{camera}")).cameras.len(), 1);
}

#[test]
fn out_of_range_subset_indices_are_errors_bound_or_not() {
    let subset = "    def GeomSubset \"S\" {\n        uniform token elementType = \"face\"\n        int[] indices = [0, 5]\n    }\n}\n";
    let body = SCENE.replacen(
        "    int[] faceVertexIndices = [0, 2, 1]\n}\n",
        &format!("    int[] faceVertexIndices = [0, 2, 1]\n{subset}"),
        1,
    );
    let err = load_body_err(&body);
    assert_error(&err, Some("/Floor/S"), "face 5 is out of range");
}

#[test]
fn a_misspelt_light_input_is_named_with_a_suggestion() {
    let desc = load_body(&SCENE.replace(
        "float inputs:radius",
        "float inputs:intensty = 5\n    float inputs:radius",
    ));
    assert_warned(
        &desc,
        &[
            "/Bulb",
            "unknown input 'inputs:intensty' for SphereLight",
            "did you mean inputs:intensity?",
        ],
    );
    let desc = load_body(&SCENE.replace(
        "float inputs:radius",
        "float inputs:glow = 5\n    float inputs:radius",
    ));
    assert_warned(&desc, &["unknown input 'inputs:glow'"]);
    assert!(
        !desc.warnings.iter().any(|w| w.contains("did you mean")),
        "{:?}",
        desc.warnings
    );
    assert!(
        load_body(SCENE).warnings.is_empty(),
        "{:?}",
        load_body(SCENE).warnings
    );
}

#[test]
fn misspelt_shader_inputs_are_named() {
    let material = "def Material \"M\" {
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader \"S\" {
        uniform token info:id = \"UsdPreviewSurface\"
        float inputs:roughnes = 0.3
        color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>
        token outputs:surface
    }
    def Shader \"T\" {
        uniform token info:id = \"UsdUVTexture\"
        asset inputs:file = @tex.png@
        token inputs:wrapz = \"clamp\"
        float3 outputs:rgb
    }
}
";
    let dir = temp_dir();
    let png = dir.join("tex.png");
    crate::imageio::write_png_rgba8(&png, &[255; 16], 2, 2).unwrap();
    let body = SCENE.replace(
        "    int[] faceVertexCounts",
        "    rel material:binding = </M>\n    int[] faceVertexCounts",
    );
    let path = dir.join("stage.usda");
    std::fs::write(&path, format!("{METRES_Y_UP}{body}{material}")).unwrap();
    let desc = super::super::load(&path).unwrap();
    assert_warned(
        &desc,
        &[
            "/M/S",
            "'inputs:roughnes' for UsdPreviewSurface",
            "did you mean inputs:roughness?",
        ],
    );
    assert_warned(
        &desc,
        &[
            "/M/T",
            "'inputs:wrapz' for UsdUVTexture",
            "did you mean inputs:wrapS?",
        ],
    );
}

#[test]
fn preview_surface_ranges() {
    let material = |input: &str| {
        format!(
            "def Material \"M\" {{\n    token outputs:surface.connect = </M/S.outputs:surface>\n    def Shader \"S\" {{\n        uniform token info:id = \"UsdPreviewSurface\"\n        {input}\n        token outputs:surface\n    }}\n}}\n"
        )
    };
    let body = SCENE.replace(
        "    int[] faceVertexCounts",
        "    rel material:binding = </M>\n    int[] faceVertexCounts",
    );
    let err = load_body_err(&format!(
        "{body}{}",
        material("float inputs:roughness = -0.2")
    ));
    assert_error(&err, Some("/M/S"), "inputs:roughness = -0.2 is negative");
    let desc = load_body(&format!(
        "{body}{}",
        material("float inputs:metallic = 1.5")
    ));
    assert_warned(
        &desc,
        &["/M/S", "inputs:metallic = 1.5 is above 1; clamped to 1"],
    );
}

#[test]
fn ignored_render_settings_are_named() {
    let settings = "def RenderSettings \"Settings\" {
    int2 resolution = (64, 32)
    float pixelAspectRatio = 2
    float4 dataWindowNDC = (0, 0, 0.5, 0.5)
    token aspectRatioConformPolicy = \"expandAperture\"
    uniform token[] includedPurposes = [\"render\", \"default\"]
}
";
    let desc = load_body(&format!("{SCENE}{settings}"));
    assert_eq!(desc.render.resolution, Some((64, 32)));
    assert_warned(
        &desc,
        &["/Settings", "pixelAspectRatio is not supported; ignored"],
    );
    assert_eq!(desc.warnings.len(), 1, "{:?}", desc.warnings);
    let window = desc
        .render
        .data_window
        .as_ref()
        .expect("the window is read");
    assert_eq!(window.ndc, [0.0, 0.0, 0.5, 0.5]);
    assert_eq!(window.prim_path, "/Settings");
    let fallbacks = settings
        .replace("float pixelAspectRatio = 2", "float pixelAspectRatio = 1")
        .replace("(0, 0, 0.5, 0.5)", "(0, 0, 1, 1)");
    let desc = load_body(&format!("{SCENE}{fallbacks}"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    assert_eq!(
        desc.render.data_window, None,
        "the whole image is no window"
    );
}

#[test]
fn data_windows_outside_the_screen_or_empty_are_refused() {
    for (window, reason) in [
        ("(-0.1, 0, 1, 1)", "overscan is not supported"),
        ("(0, 0, 1.5, 1)", "overscan is not supported"),
        ("(0.5, 0, 0.5, 1)", "is empty"),
        ("(0, 0.7, 1, 0.2)", "is empty"),
    ] {
        let settings = format!(
            "def RenderSettings \"Settings\" {{\n    float4 dataWindowNDC = {window}\n}}\n"
        );
        let err = load_body_err(&format!("{SCENE}{settings}"));
        assert_error(&err, Some("/Settings"), reason);
    }
}

#[test]
fn a_product_window_overrides_the_settings_window() {
    let settings = "def RenderSettings \"Settings\" {
    float4 dataWindowNDC = (0, 0, 0.5, 0.5)
    rel products = </Product>
}
def RenderProduct \"Product\" {
    float4 dataWindowNDC = (0, 0, 1, 1)
}
";
    let desc = load_body(&format!("{SCENE}{settings}"));
    assert_eq!(
        desc.render.data_window, None,
        "the product's whole image wins"
    );
    let narrower = settings.replace("(0, 0, 1, 1)", "(0.25, 0.5, 0.75, 1)");
    let desc = load_body(&format!("{SCENE}{narrower}"));
    let w = desc.render.data_window.expect("the product's window");
    assert_eq!(
        (w.ndc, w.prim_path.as_str()),
        ([0.25, 0.5, 0.75, 1.0], "/Product")
    );
}

#[test]
fn non_regular_files_are_refused() {
    let err = super::super::load(Path::new("/dev/zero")).unwrap_err();
    assert!(err.to_string().contains("not a regular file"), "{err}");
    let dir = temp_dir();
    // A FIFO no one writes to: reading it would block forever.
    let fifo = std::process::Command::new("mkfifo")
        .arg(dir.join("zero.usda"))
        .status()
        .unwrap();
    assert!(fifo.success());
    let path = dir.join("main.usda");
    let body = "def Xform \"A\" ( references = @zero.usda@</A> ) {}\n";
    std::fs::write(&path, format!("{METRES_Y_UP}{body}")).unwrap();
    let err = super::super::load(&path).unwrap_err();
    assert_one_line(&err, "main.usda");
    assert!(err.to_string().contains("is not a regular file"), "{err}");
}

/// The Cornell box written as a crate file by usd-core (`tests/data/usdc/`).
fn crate_bytes() -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usdc/cornell-box.usdc");
    std::fs::read(path).unwrap()
}

#[test]
fn crate_files_load_as_their_text() {
    // Written by usd-core (`Sdf.Layer.Export`) from the scenes of the same name.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for name in ["cornell-box", "materials"] {
        let desc = super::super::load(&root.join(format!("tests/data/usdc/{name}.usdc"))).unwrap();
        let reference = super::super::load(&root.join(format!("scenes/{name}.usda"))).unwrap();
        assert_eq!(paths(&desc), paths(&reference));
        for (a, b) in desc.meshes.iter().zip(&reference.meshes) {
            assert_eq!(a.positions, b.positions, "{}", a.prim_path);
            assert_eq!(a.indices, b.indices, "{}", a.prim_path);
        }
        assert_eq!(desc.lights.len(), reference.lights.len(), "{name}");
    }
}

#[test]
fn corrupt_crate_files_are_one_line_errors() {
    // Every byte of the header and table of contents, and a seeded sample of the rest,
    // overwritten with values that break counts and offsets; and every truncation length.
    let good = crate_bytes();
    let dir = temp_dir();
    let path = dir.join("bad.usdc");
    // A fixed sequence of positions past the header (a multiplicative hash of k).
    let position = |k: usize| (k.wrapping_mul(2_654_435_761) >> 7) % good.len();
    let mut cases: Vec<Vec<u8>> = Vec::new();
    for len in (0..good.len()).step_by(97) {
        cases.push(good[..len].to_vec());
    }
    for k in 0..200 {
        let at = if k < 120 { k } else { position(k) };
        for value in [0xff, 0x7f, 0x00] {
            let mut bad = good.clone();
            bad[at] = value;
            cases.push(bad);
        }
    }
    let mut refused = 0;
    for bad in cases {
        std::fs::write(&path, &bad).unwrap();
        if let Err(e) = super::super::load(&path) {
            assert_one_line(&e, "bad.usdc");
            refused += 1;
        }
    }
    assert!(refused > 100, "only {refused} corrupt files refused");
}

#[test]
fn crate_files_written_by_openusd_pass_the_checks() {
    for scene in [
        "scenes/cornell-box.usda",
        "scenes/materials.usda",
        "scenes/room.usda",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
        let data = openusd::usda::parse(&std::fs::read_to_string(path).unwrap()).unwrap();
        let mut bytes = Vec::new();
        openusd::usdc::CrateWriter::write(&data, &mut std::io::Cursor::new(&mut bytes)).unwrap();
        super::super::resolver::check_layer(&bytes).unwrap_or_else(|e| panic!("{scene}: {e}"));
    }
}
