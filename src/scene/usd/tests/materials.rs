//! Material bindings, UsdPreviewSurface and the `spectral:*` shaders.

use super::*;
use crate::desc::{IorDesc, MaterialDesc, MaterialKind, PreviewSurfaceDesc, SpectrumDesc};

/// A Material `name` whose surface is a Shader with `id` and the `inputs` lines.
fn material(name: &str, id: &str, inputs: &str) -> String {
    format!(
        r#"def Material "{name}" {{
    token outputs:surface.connect = </Looks/{name}/S.outputs:surface>
    def Shader "S" {{
        uniform token info:id = "{id}"
        {inputs}
        token outputs:surface
    }}
}}
"#
    )
}

/// A triangle mesh `name` bound to `/Looks/<material>` (no binding when empty).
fn bound_mesh(name: &str, material: &str) -> String {
    let binding = if material.is_empty() {
        String::new()
    } else {
        format!("rel material:binding = </Looks/{material}>")
    };
    format!(
        r#"def Mesh "{name}" {{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    {binding}
}}
"#
    )
}

/// The material bound to mesh `/<name>`.
fn material_of<'a>(desc: &'a SceneDescription, name: &str) -> &'a MaterialDesc {
    let index = mesh(desc, &format!("/{name}")).material.expect("bound");
    &desc.materials[index]
}

/// Loads `/Looks/<name>` materials (`id`, `inputs`) each bound to a mesh `/<name>`.
fn load_materials(materials: &[(&str, &str, &str)]) -> SceneDescription {
    let looks: String = materials
        .iter()
        .map(|(n, id, inputs)| material(n, id, inputs))
        .collect();
    let meshes: String = materials.iter().map(|(n, ..)| bound_mesh(n, n)).collect();
    load_body(&format!("def Scope \"Looks\" {{\n{looks}}}\n{meshes}"))
}

#[test]
fn spectral_material_vocabulary() {
    let desc = load_materials(&[
        (
            "DarkSkin",
            "spectral:diffuse",
            r#"token inputs:reflectance:spectrum = "colorchecker/dark_skin"
        float inputs:roughness = 0.2"#,
        ),
        ("DefaultDiffuse", "spectral:diffuse", ""),
        (
            "Rgb",
            "spectral:diffuse",
            "color3f inputs:reflectance = (0.1, 0.2, 0.3)",
        ),
        (
            "Gold",
            "spectral:conductor",
            r#"token inputs:metal = "Au"
        float inputs:roughness = 0.1"#,
        ),
        (
            "Custom",
            "spectral:conductor",
            r#"token inputs:eta:spectrum = "metal/Ag-eta"
        token inputs:k:spectrum = "metal/Ag-k""#,
        ),
        (
            "Bk7",
            "spectral:dielectric",
            r#"token inputs:glass = "BK7"
        bool inputs:thin = 1"#,
        ),
        (
            "Sellmeier",
            "spectral:dielectric",
            r#"float3 inputs:sellmeierB = (1.03961212, 0.231792344, 1.01046945)
        float3 inputs:sellmeierC = (0.00600069867, 0.0200179144, 103.560653)"#,
        ),
        ("Water", "spectral:dielectric", "float inputs:ior = 1.33"),
        ("Glass", "spectral:dielectric", ""),
        (
            "Plastic",
            "spectral:plastic",
            r#"float2[] inputs:reflectance:samples = [(400, 0.1), (700, 0.9)]
        float inputs:ior = 1.4
        float inputs:roughness = 0.3"#,
        ),
        ("DefaultPlastic", "spectral:plastic", ""),
    ]);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let kind = |name: &str| material_of(&desc, name).kind.clone();
    assert!(
        matches!(kind("DarkSkin"), MaterialKind::Diffuse { reflectance: SpectrumDesc::Named(n), roughness }
        if n == "colorchecker/dark_skin" && roughness == 0.2)
    );
    assert!(
        matches!(kind("DefaultDiffuse"), MaterialKind::Diffuse { reflectance: SpectrumDesc::Rgb([0.5, 0.5, 0.5]), roughness }
        if roughness == 0.0)
    );
    assert!(matches!(
        kind("Rgb"),
        MaterialKind::Diffuse {
            reflectance: SpectrumDesc::Rgb([0.1, 0.2, 0.3]),
            ..
        }
    ));
    assert!(
        matches!(kind("Gold"), MaterialKind::Conductor { eta: SpectrumDesc::Named(e), k: SpectrumDesc::Named(k), roughness }
        if e == "metal/Au" && k == "metal/Au" && roughness == 0.1)
    );
    assert!(
        matches!(kind("Custom"), MaterialKind::Conductor { eta: SpectrumDesc::Named(e), k: SpectrumDesc::Named(k), .. }
        if e == "metal/Ag-eta" && k == "metal/Ag-k")
    );
    assert!(
        matches!(kind("Bk7"), MaterialKind::Dielectric { ior: IorDesc::Glass(g), thin: true, .. } if g == "BK7")
    );
    assert!(
        matches!(kind("Sellmeier"), MaterialKind::Dielectric { ior: IorDesc::Sellmeier { b, c }, thin: false, .. }
        if (b[0] - 1.039_612).abs() < 1e-6 && (c[2] - 103.560_65).abs() < 1e-4)
    );
    assert!(
        matches!(kind("Water"), MaterialKind::Dielectric { ior: IorDesc::Constant(x), .. } if x == 1.33)
    );
    assert!(
        matches!(kind("Glass"), MaterialKind::Dielectric { ior: IorDesc::Constant(x), roughness, thin: false }
        if x == 1.5 && roughness == 0.0)
    );
    assert!(
        matches!(kind("Plastic"), MaterialKind::Plastic { reflectance: SpectrumDesc::Samples(s), ior, roughness }
        if s == vec![(400.0, 0.1), (700.0, 0.9)] && ior == 1.4 && roughness == 0.3)
    );
    assert!(
        matches!(kind("DefaultPlastic"), MaterialKind::Plastic { reflectance: SpectrumDesc::Rgb([0.5, 0.5, 0.5]), ior, .. }
        if ior == 1.5)
    );
}

#[test]
fn preview_surface_inputs_and_emission() {
    let desc = load_materials(&[
        (
            "Lamp",
            "UsdPreviewSurface",
            r#"color3f inputs:diffuseColor = (0.2, 0.3, 0.4)
        color3f inputs:emissiveColor = (10, 9, 8)
        float inputs:metallic = 1
        float inputs:roughness = 0.25
        float inputs:clearcoat = 0.5
        float inputs:clearcoatRoughness = 0.1
        float inputs:opacity = 0.9
        float inputs:opacityThreshold = 0.2
        float inputs:ior = 1.7
        int inputs:useSpecularWorkflow = 1
        color3f inputs:specularColor = (0.5, 0.5, 0.5)"#,
        ),
        ("Default", "UsdPreviewSurface", ""),
    ]);
    let lamp = material_of(&desc, "Lamp");
    assert_eq!(lamp.emission, Some([10.0, 9.0, 8.0]));
    let expected = PreviewSurfaceDesc {
        diffuse_color: [0.2, 0.3, 0.4],
        emissive_color: [10.0, 9.0, 8.0],
        use_specular_workflow: true,
        specular_color: [0.5; 3],
        metallic: 1.0,
        roughness: 0.25,
        clearcoat: 0.5,
        clearcoat_roughness: 0.1,
        opacity: 0.9,
        opacity_threshold: 0.2,
        ior: 1.7,
        ..PreviewSurfaceDesc::default()
    };
    assert!(matches!(&lamp.kind, MaterialKind::PreviewSurface(p) if *p == expected));
    let default = material_of(&desc, "Default");
    assert_eq!(default.emission, None);
    assert!(
        matches!(&default.kind, MaterialKind::PreviewSurface(p) if *p == PreviewSurfaceDesc::default())
    );
}

#[test]
fn a_missing_texture_file_names_the_shader_and_the_file() {
    let err = load_body_err(WOOD);
    let text = err.to_string();
    assert!(text.contains("/Looks/Wood/Tex"), "{text}");
    assert!(text.contains("wood.png"), "{text}");
}

#[test]
fn texture_inputs_are_read_and_interface_inputs_resolve() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("wood.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let text = format!("{METRES_Y_UP}{WOOD}");
    let path = dir.join("stage.usda");
    std::fs::write(&path, text).unwrap();
    let desc = super::super::load(&path).expect("loads");
    let wood = material_of(&desc, "Wood");
    let MaterialKind::PreviewSurface(p) = &wood.kind else {
        panic!("preview surface")
    };
    assert_eq!(p.diffuse_color, PreviewSurfaceDesc::default().diffuse_color);
    assert_eq!(p.specular_color, [0.7, 0.6, 0.5]);
    let tex = p.texture("diffuseColor").expect("a diffuseColor texture");
    assert_eq!(tex.file, dir.join("wood.png"));
    assert_eq!(tex.shader_path, "/Looks/Wood/Tex");
    assert_eq!(tex.wrap_s, crate::desc::Wrap::Mirror);
    assert_eq!(tex.wrap_t, crate::desc::Wrap::Repeat);
    assert_eq!(tex.color_space, crate::desc::ColorSpace::Raw);
    assert_eq!(tex.st_primvar, "uv");
    assert_eq!(tex.scale, [2.0, 2.0, 2.0, 1.0]);
    assert_eq!(tex.bias, [0.0, 0.1, 0.0, 0.0]);
    let opacity = p.texture("opacity").expect("an opacity texture");
    assert_eq!(opacity.channel, crate::desc::TextureChannel::A);
    assert!(
        desc.warnings.iter().all(|w| !w.contains("not supported")),
        "{:?}",
        desc.warnings
    );
}

/// A UsdUVTexture without `inputs:file` (the usd-wg shader ball authors the file only in
/// variants) outputs its fallback, with a warning naming the node; scale and bias do not
/// apply to it.
#[test]
fn a_texture_node_without_a_file_is_its_fallback() {
    let body = WOOD.replace(
        "asset inputs:file = @wood.png@",
        "float4 inputs:fallback = (0.25, 0.5, 0.75, 0.4)",
    );
    let path = temp_dir().join("no_file.usda");
    std::fs::write(&path, format!("{METRES_Y_UP}{body}")).unwrap();
    let desc = super::super::load(&path).expect("loads");
    let MaterialKind::PreviewSurface(p) = &material_of(&desc, "Wood").kind else {
        panic!("preview surface")
    };
    let tex = p.texture("diffuseColor").expect("the node is kept");
    assert!(tex.file.as_os_str().is_empty());
    assert!(
        desc.warnings.iter().any(|w| w.contains("/Looks/Wood/Tex")
            && w.contains("no inputs:file; its fallback [0.25, 0.5, 0.75, 0.4]")),
        "{:?}",
        desc.warnings
    );
    let input = crate::texture::TextureCache::default().input(tex).unwrap();
    let uv = glam::Vec2::new(0.3, 0.8).into();
    assert_eq!(input.rgba(uv), [0.25, 0.5, 0.75, 0.4]);
    crate::scene::build(&desc, Some((4, 4))).expect("builds");
}

#[test]
fn an_unknown_wrap_token_is_an_error() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("wood.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let text = format!("{METRES_Y_UP}{}", WOOD.replace("\"mirror\"", "\"wrap\""));
    let path = dir.join("stage.usda");
    std::fs::write(&path, text).unwrap();
    let err = super::super::load(&path).expect_err("bad wrap");
    assert_one_line(&err, "stage.usda");
    let text = err.to_string();
    assert!(
        text.contains("/Looks/Wood/Tex") && text.contains("wrapS 'wrap'"),
        "{text}"
    );
}

/// `WOOD` with a `spectral:plastic` surface whose reflectance and roughness are textured.
fn spectral_wood(ior_line: &str) -> String {
    let surface = format!(
        "uniform token info:id = \"spectral:plastic\"\n            \
         color3f inputs:reflectance.connect = </Looks/Wood/Tex.outputs:rgb>\n            \
         float inputs:roughness.connect = </Looks/Wood/Tex.outputs:r>\n            {ior_line}"
    );
    let start = WOOD
        .find("uniform token info:id = \"UsdPreviewSurface\"")
        .unwrap();
    let end = WOOD[start..].find("token outputs:surface").unwrap() + start;
    format!("{}{surface}\n            {}", &WOOD[..start], &WOOD[end..])
}

#[test]
fn spectral_shaders_read_textures_on_reflectance_and_roughness() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("wood.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let path = dir.join("stage.usda");
    let text = spectral_wood("float inputs:ior = 1.4");
    std::fs::write(&path, format!("{METRES_Y_UP}{text}")).unwrap();
    let desc = super::super::load(&path).expect("loads");
    let wood = material_of(&desc, "Wood");
    let MaterialKind::Plastic { ior, .. } = &wood.kind else {
        panic!("plastic: {:?}", wood.kind)
    };
    assert_eq!(*ior, 1.4);
    let reflectance = wood.texture("reflectance").expect("textured reflectance");
    assert_eq!(reflectance.channel, crate::desc::TextureChannel::Rgb);
    assert_eq!(reflectance.shader_path, "/Looks/Wood/Tex");
    let roughness = wood.texture("roughness").expect("textured roughness");
    assert_eq!(roughness.channel, crate::desc::TextureChannel::R);
    assert_eq!(wood.all_textures().count(), 2);
    // A texture on an input that only takes a value is an error naming the input.
    let bad = spectral_wood("float inputs:ior.connect = </Looks/Wood/Tex.outputs:r>");
    std::fs::write(&path, format!("{METRES_Y_UP}{bad}")).unwrap();
    let err = super::super::load(&path).expect_err("ior cannot be textured");
    assert_one_line(&err, "stage.usda");
    let text = err.to_string();
    for part in [
        "/Looks/Wood/S",
        "inputs:ior",
        "spectral:plastic",
        "inputs:reflectance, inputs:roughness",
    ] {
        assert!(text.contains(part), "'{part}' not in {text}");
    }
}

/// A UsdPreviewSurface with textured diffuseColor and opacity, and an interface input.
const WOOD: &str = r#"def Scope "Looks" {
    def Material "Wood" {
        color3f inputs:tint = (0.7, 0.6, 0.5)
        token outputs:surface.connect = </Looks/Wood/S.outputs:surface>
        def Shader "S" {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Looks/Wood/Tex.outputs:rgb>
            float inputs:opacity.connect = </Looks/Wood/Tex.outputs:a>
            color3f inputs:specularColor.connect = </Looks/Wood.inputs:tint>
            token outputs:surface
        }
        def Shader "Reader" {
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "uv"
            float2 outputs:result
        }
        def Shader "Tex" {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @wood.png@
            float2 inputs:st.connect = </Looks/Wood/Reader.outputs:result>
            token inputs:wrapS = "mirror"
            token inputs:sourceColorSpace = "raw"
            float4 inputs:scale = (2, 2, 2, 1)
            float4 inputs:bias = (0, 0.1, 0, 0)
            float3 outputs:rgb
            float outputs:a
        }
    }
}
def Mesh "Wood" {
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    rel material:binding = </Looks/Wood>
}
"#;

#[test]
fn bindings_are_inherited_deduplicated_and_optional() {
    let desc = load_body(&format!(
        r#"def Scope "Looks" {{
{}{}}}
def Xform "Group" {{
    rel material:binding = </Looks/A>
    {}{}
    def Xform "Strong" {{
        rel material:binding = </Looks/B>
        {}
    }}
}}
def Xform "Forced" {{
    rel material:binding = </Looks/A> (
        bindMaterialAs = "strongerThanDescendants"
    )
    {}
}}
{}"#,
        material("A", "spectral:diffuse", ""),
        material("B", "spectral:plastic", ""),
        bound_mesh("One", ""),
        bound_mesh("Two", ""),
        bound_mesh("Three", ""),
        bound_mesh("Four", "B"),
        bound_mesh("Unbound", ""),
    ));
    let index = |path: &str| mesh(&desc, path).material;
    assert_eq!(desc.materials.len(), 2);
    assert_eq!(index("/Group/One"), index("/Group/Two"));
    assert_eq!(
        desc.materials[index("/Group/One").expect("A")].prim_path,
        "/Looks/A"
    );
    assert_eq!(
        desc.materials[index("/Group/Strong/Three").expect("B")].prim_path,
        "/Looks/B"
    );
    assert_eq!(
        desc.materials[index("/Forced/Four").expect("A")].prim_path,
        "/Looks/A"
    );
    assert_eq!(index("/Unbound"), None);
}

/// A Material `name` whose diffuseColor texture reads primvar `varname` (one reader per
/// entry of `varnames` feeding one texture each: diffuseColor, then roughness).
fn primvar_material(name: &str, varnames: &[&str]) -> String {
    let inputs = ["color3f inputs:diffuseColor", "float inputs:roughness"];
    let outputs = ["rgb", "r"];
    let mut nodes = String::new();
    let mut connections = String::new();
    for (k, varname) in varnames.iter().enumerate() {
        connections += &format!(
            "        {}.connect = </Looks/{name}/Tex{k}.outputs:{}>\n",
            inputs[k], outputs[k]
        );
        nodes += &format!(
            r#"    def Shader "Reader{k}" {{
        uniform token info:id = "UsdPrimvarReader_float2"
        token inputs:varname = "{varname}"
        float2 outputs:result
    }}
    def Shader "Tex{k}" {{
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @tex.png@
        float2 inputs:st.connect = </Looks/{name}/Reader{k}.outputs:result>
        float3 outputs:rgb
        float outputs:r
    }}
"#
        );
    }
    format!(
        r#"def Material "{name}" {{
    token outputs:surface.connect = </Looks/{name}/S.outputs:surface>
    def Shader "S" {{
        uniform token info:id = "UsdPreviewSurface"
{connections}        token outputs:surface
    }}
{nodes}}}
"#
    )
}

/// A quad (two triangles) with primvars `st` (vertex), `uv1` (faceVarying, indexed), `map1`
/// (uniform) and `flat` (constant), bound to `/Looks/<material>`.
fn primvar_mesh(name: &str, material: &str) -> String {
    format!(
        r#"def Mesh "{name}" {{
    int[] faceVertexCounts = [3, 3]
    int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (
        interpolation = "vertex"
    )
    float2[] primvars:uv1 = [(5, 5), (6, 5), (6, 6)] (
        interpolation = "faceVarying"
    )
    int[] primvars:uv1:indices = [0, 1, 2, 0, 2, 1]
    texCoord2f[] primvars:map1 = [(0.25, 0.5), (0.75, 0.5)] (
        interpolation = "uniform"
    )
    texCoord2d[] primvars:flat = [(0.5, 0.125)] (
        interpolation = "constant"
    )
    rel material:binding = </Looks/{material}>
}}
"#
    )
}

#[test]
fn meshes_keep_the_texcoord_primvar_their_material_reads() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("tex.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let looks: String = [
        ("St", vec!["st"]),
        ("Uv1", vec!["uv1"]),
        ("Map1", vec!["map1", "map1"]),
        ("Flat", vec!["flat"]),
        ("Missing", vec!["nowhere"]),
    ]
    .iter()
    .map(|(n, v)| primvar_material(n, v))
    .collect();
    let meshes: String = ["St", "Uv1", "Map1", "Flat", "Missing"]
        .iter()
        .map(|n| primvar_mesh(n, n))
        .collect();
    let path = dir.join("stage.usda");
    let text = format!("{METRES_Y_UP}def Scope \"Looks\" {{\n{looks}}}\n{meshes}");
    std::fs::write(&path, text).unwrap();
    let desc = super::super::load(&path).expect("loads");
    let v = |x: f32, y: f32| glam::Vec2::new(x, y);
    let uvs = |name: &str| mesh(&desc, name).uvs.clone();
    assert_eq!(material_of(&desc, "Uv1").texcoord, "uv1");
    assert_eq!(
        uvs("/St").unwrap()[1],
        [v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]
    );
    assert_eq!(
        uvs("/Uv1").unwrap()[1],
        [v(5.0, 5.0), v(6.0, 6.0), v(6.0, 5.0)]
    );
    assert_eq!(uvs("/Map1").unwrap()[0], [v(0.25, 0.5); 3]);
    assert_eq!(uvs("/Map1").unwrap()[1], [v(0.75, 0.5); 3]);
    assert_eq!(uvs("/Flat").unwrap()[1], [v(0.5, 0.125); 3]);
    assert!(uvs("/Missing").is_none());
    let missing: Vec<_> = desc
        .warnings
        .iter()
        .filter(|w| w.contains("primvars:nowhere"))
        .collect();
    assert_eq!(missing.len(), 1, "{:?}", desc.warnings);
    assert!(missing[0].contains("/Missing"), "{missing:?}");
}

#[test]
fn a_material_reading_two_texcoord_primvars_is_an_error() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("tex.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let text = format!(
        "{METRES_Y_UP}def Scope \"Looks\" {{\n{}}}\n{}",
        primvar_material("Mixed", &["st", "uv1"]),
        primvar_mesh("Q", "Mixed")
    );
    let path = dir.join("stage.usda");
    std::fs::write(&path, text).unwrap();
    let err = super::super::load(&path).expect_err("two primvars");
    assert_one_line(&err, "stage.usda");
    let text = err.to_string();
    for part in ["/Looks/Mixed", "primvars:st", "primvars:uv1", "only one"] {
        assert!(text.contains(part), "'{part}' not in {text}");
    }
}

/// `WOOD` with a UsdTransform2d between the reader and the texture (`transform` lines).
fn transformed_wood(transform: &str) -> String {
    let node = format!(
        r#"def Shader "T" {{
            uniform token info:id = "UsdTransform2d"
            float2 inputs:in.connect = </Looks/Wood/Reader.outputs:result>
            {transform}
            float2 outputs:result
        }}
        def Shader "Tex" {{"#
    );
    WOOD.replace("def Shader \"Tex\" {", &node).replace(
        "float2 inputs:st.connect = </Looks/Wood/Reader.outputs:result>",
        "float2 inputs:st.connect = </Looks/Wood/T.outputs:result>",
    )
}

#[test]
fn transform2d_nodes_are_read_and_their_inputs_must_be_values() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("wood.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let path = dir.join("stage.usda");
    let ok =
        transformed_wood("float inputs:rotation = 90\n            float2 inputs:scale = (2, 1)");
    std::fs::write(&path, format!("{METRES_Y_UP}{ok}")).unwrap();
    let desc = super::super::load(&path).expect("loads");
    let MaterialKind::PreviewSurface(p) = &material_of(&desc, "Wood").kind else {
        panic!("preview surface")
    };
    let tex = p.texture("diffuseColor").expect("textured");
    assert_eq!(tex.st_primvar, "uv");
    let t = tex.st_transform.expect("a transform");
    let q = t.transform_point2(glam::Vec2::new(1.0, 1.0));
    assert!((q - glam::Vec2::new(-1.0, 2.0)).length() < 1e-6, "{q}");
    let bad = transformed_wood("float inputs:rotation.connect = </Looks/Wood/Tex.outputs:r>");
    std::fs::write(&path, format!("{METRES_Y_UP}{bad}")).unwrap();
    let err = super::super::load(&path).expect_err("a driven rotation");
    assert_one_line(&err, "stage.usda");
    let text = err.to_string();
    assert!(
        text.contains("/Looks/Wood/T") && text.contains("inputs:rotation"),
        "{text}"
    );
}

#[test]
fn geom_subsets_keep_the_primvar_of_their_own_material() {
    let dir = temp_dir();
    crate::imageio::write_png_rgba8(&dir.join("tex.png"), &[255, 0, 0, 255], 1, 1).unwrap();
    let subset = r#"    def GeomSubset "Second" {
        uniform token elementType = "face"
        uniform token familyName = "materialBind"
        int[] indices = [1]
        rel material:binding = </Looks/Uv1>
    }
}"#;
    let mesh_text = primvar_mesh("Q", "St");
    let mesh_text = format!("{}{subset}\n", &mesh_text[..mesh_text.rfind('}').unwrap()]);
    let looks = primvar_material("St", &["st"]) + &primvar_material("Uv1", &["uv1"]);
    let path = dir.join("stage.usda");
    let text = format!("{METRES_Y_UP}def Scope \"Looks\" {{\n{looks}}}\n{mesh_text}");
    std::fs::write(&path, text).unwrap();
    let desc = super::super::load(&path).expect("loads");
    let v = |x: f32, y: f32| glam::Vec2::new(x, y);
    let first = mesh(&desc, "/Q").uvs.clone().expect("st");
    let second = mesh(&desc, "/Q/Second").uvs.clone().expect("uv1");
    assert_eq!(first, vec![[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)]]);
    assert_eq!(second, vec![[v(5.0, 5.0), v(6.0, 6.0), v(6.0, 5.0)]]);
}
