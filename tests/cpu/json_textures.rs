//! Textures in JSON scenes (issue 14) through the loader: a Phong colour
//! given as `{"texture": ...}` and a user shader's `u32` Params field given
//! one, what they load as (the texels decoded from the file, the sampler
//! and scale the JSON names, one texture per file, the files a watcher
//! needs), and every kind of bad input with the file and JSON path it
//! names. The command line's errors are in `tests/cli/json_textures.rs`.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use glam::{DVec2, Vec3};
use penumbra::loaders::{load_scene, LoadOptions, Loaded};
use penumbra::scene::{Filter, ParamValue, Sampler, Shader, TextureRef, Wrap};
use penumbra::SceneError;
use serde_json::{json, Value};
use tempfile::TempDir;

/// A 3×2 PNG whose texels all differ: texel (x, y) is
/// `(10 + 40x, 20 + 50y, 7, 255 − x − y)`.
fn png() -> Vec<u8> {
    let img = image::RgbaImage::from_fn(3, 2, |x, y| {
        image::Rgba([
            (10 + 40 * x) as u8,
            (20 + 50 * y) as u8,
            7,
            (255 - x - y) as u8,
        ])
    });
    let mut out = Vec::new();
    img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// A scene with `shaders`, a plane using `floor` and a sphere using `ball`.
fn scene(shaders: Value) -> Value {
    json!({
        "camera": {"position": [0, 3, 8], "look_at": [0, 0, 0], "width": 16, "height": 16},
        "shaders": shaders,
        "objects": [
            {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"},
            {"type": "sphere", "center": [0, 1, 0], "radius": 1, "shader": "ball"}
        ],
        "lights": [{"type": "point", "position": [2, 3, 4]}]
    })
}

/// A user shader with a texture parameter `t` and a colour `c`.
const PAINTED: &str = "struct Params { t: u32, c: vec3<f32>, }
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return texture_at(p.t, s).rgb * p.c * max(dot(s.normal, l.to_light), 0.0);
}
";

/// Writes `json` as `scene.json` into a fresh folder, with `files` (name,
/// bytes) beside it.
fn write(json: &Value, files: &[(&str, &[u8])]) -> (TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    let path = dir.path().join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(json).unwrap()).unwrap();
    (dir, path)
}

fn load(json: &Value, files: &[(&str, &[u8])]) -> (TempDir, PathBuf, Loaded) {
    let (dir, path) = write(json, files);
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    (dir, path, loaded)
}

/// The error loading `json` with `files`, checked to name the scene file
/// and `field`, and to contain every string of `must`.
#[track_caller]
fn fails(json: &Value, files: &[(&str, &[u8])], field: &str, must: &[&str]) -> SceneError {
    let (_dir, path) = write(json, files);
    let e = load_scene(&path, &LoadOptions::default()).expect_err("the scene must not load");
    assert_eq!(e.file, path, "{e}");
    assert_eq!(e.field, field, "{e}");
    for m in must {
        assert!(e.to_string().contains(m), "{e} should mention {m:?}");
    }
    e
}

fn phong(s: &Shader) -> &penumbra::scene::Phong {
    match s {
        Shader::Phong(p) | Shader::BlinnPhong(p) => p,
        other => panic!("not a Phong shader: {other:?}"),
    }
}

/// The shaders `floor` (Phong, its diffuse `diffuse`) and `ball` (plain).
fn floor_with(diffuse: Value) -> Value {
    scene(json!({
        "floor": {"type": "phong", "diffuse": diffuse, "ambient": [0.1, 0.1, 0.1]},
        "ball": {"type": "blinn_phong", "diffuse": [0.5, 0.5, 0.5]}
    }))
}

#[test]
fn a_textured_colour_loads_the_file_as_an_srgb_texture_with_the_default_sampler() {
    let (dir, _path, loaded) = load(
        &floor_with(json!({"texture": "wood.png"})),
        &[("wood.png", &png())],
    );
    let s = &loaded.scene;
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!((t.width, t.height), (3, 2));
    assert!(t.srgb, "a colour texture is sRGB");
    assert_eq!(t.texels[0], [10, 20, 7, 255]);
    assert_eq!(t.texels[5], [90, 70, 7, 252], "row 1, column 2");
    let file = dir.path().join("wood.png");
    assert_eq!(t.file.as_deref(), Some(file.as_path()));
    assert!(t.label.contains("wood.png"), "{}", t.label);
    // Names are sorted: ball is shader 0, floor shader 1.
    let p = phong(&s.shaders[1]);
    assert_eq!(p.diffuse, Vec3::ONE, "a textured colour is (1, 1, 1)");
    assert_eq!(p.ambient, Vec3::splat(0.1), "the plain colours stay");
    assert_eq!(p.textures.diffuse, Some(TextureRef::new(0)));
    assert_eq!(p.textures.ambient, None);
    assert_eq!(p.textures.specular, None);
    assert_eq!(
        TextureRef::new(0).sampler,
        Sampler {
            mag: Filter::Linear,
            min: Filter::Linear,
            mip: Some(Filter::Linear),
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
        },
        "the default is trilinear and repeating"
    );
    // The watcher needs the texture file among the files read.
    assert!(loaded.files.contains(&file), "{:?}", loaded.files);
    assert!(phong(&s.shaders[0]).textures.diffuse.is_none());
}

#[test]
fn filter_wrap_and_scale_become_the_sampler_and_the_transform() {
    let cases = [
        (json!("nearest"), Filter::Nearest, Filter::Nearest, None),
        (
            json!("bilinear"),
            Filter::Linear,
            Filter::Linear,
            Some(Filter::Nearest),
        ),
        (
            json!("trilinear"),
            Filter::Linear,
            Filter::Linear,
            Some(Filter::Linear),
        ),
    ];
    for (filter, mag, min, mip) in cases {
        let (_d, _p, loaded) = load(
            &floor_with(
                json!({"texture": "w.png", "filter": filter, "wrap": "mirrored_repeat", "scale": 0.25}),
            ),
            &[("w.png", &png())],
        );
        let t = phong(&loaded.scene.shaders[1]).textures.diffuse.unwrap();
        assert_eq!(
            t.sampler,
            Sampler {
                mag,
                min,
                mip,
                wrap_u: Wrap::MirroredRepeat,
                wrap_v: Wrap::MirroredRepeat
            },
            "{filter}"
        );
        assert_eq!(t.transform.scale, DVec2::splat(0.25));
        assert_eq!(t.transform.offset, DVec2::ZERO);
        assert_eq!(t.transform.rotation, 0.0);
        assert_eq!(t.tex_coord, 0);
    }
    let (_d, _p, loaded) = load(
        &floor_with(json!({"texture": "w.png", "wrap": ["clamp", "repeat"], "scale": [2, -3]})),
        &[("w.png", &png())],
    );
    let t = phong(&loaded.scene.shaders[1]).textures.diffuse.unwrap();
    assert_eq!(
        (t.sampler.wrap_u, t.sampler.wrap_v),
        (Wrap::ClampToEdge, Wrap::Repeat)
    );
    assert_eq!(t.transform.scale, DVec2::new(2.0, -3.0));
}

#[test]
fn a_file_named_twice_is_one_texture_and_every_colour_can_be_textured() {
    let shaders = json!({
        "floor": {"type": "phong",
                  "ambient": {"texture": "a.png"},
                  "diffuse": {"texture": "./a.png", "filter": "nearest"},
                  "specular": {"texture": "sub/b.png"}},
        "ball": {"type": "blinn_phong", "diffuse": {"texture": "sub/../a.png"}}
    });
    let (dir, _p, loaded) = load(&scene(shaders), &[("a.png", &png()), ("sub/b.png", &png())]);
    let s = &loaded.scene;
    assert_eq!(s.textures.len(), 2, "a.png once, b.png once");
    let ball = phong(&s.shaders[0]);
    let floor = phong(&s.shaders[1]);
    // Shaders load in name order: ball first, so a.png is texture 0.
    assert_eq!(ball.textures.diffuse.unwrap().texture, 0);
    assert_eq!(floor.textures.ambient.unwrap().texture, 0);
    assert_eq!(floor.textures.diffuse.unwrap().texture, 0);
    assert_eq!(floor.textures.specular.unwrap().texture, 1);
    assert_eq!(
        (floor.ambient, floor.diffuse, floor.specular),
        (Vec3::ONE, Vec3::ONE, Vec3::ONE)
    );
    // The same file with two samplers: two uses of one texture.
    assert_ne!(
        floor.textures.ambient.unwrap().sampler,
        floor.textures.diffuse.unwrap().sampler
    );
    let files: Vec<_> = loaded
        .files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "png"))
        .collect();
    assert_eq!(files.len(), 2, "{:?}", loaded.files);
    assert!(s.textures[1]
        .file
        .as_ref()
        .unwrap()
        .starts_with(dir.path().join("sub")));
}

#[test]
fn a_u32_params_field_takes_a_texture() {
    let shaders = json!({
        "floor": {"type": "wgsl", "file": "painted.wgsl",
                  "params": {"t": {"texture": "w.png", "filter": "nearest", "wrap": "clamp", "scale": [1, 2]}, "c": [1, 1, 1]}},
        "ball": {"type": "phong", "diffuse": {"texture": "w.png"}}
    });
    let (_d, _p, loaded) = load(
        &scene(shaders),
        &[("w.png", &png()), ("painted.wgsl", PAINTED.as_bytes())],
    );
    let s = &loaded.scene;
    assert_eq!(s.textures.len(), 1, "one file, one texture");
    let Shader::Wgsl(w) = &s.shaders[1] else {
        panic!("floor is the wgsl shader")
    };
    let ParamValue::Texture(t) = w.values[0] else {
        panic!("t is a texture: {:?}", w.values)
    };
    assert_eq!(t.texture, 0);
    assert_eq!(
        t.sampler,
        Sampler {
            mag: Filter::Nearest,
            min: Filter::Nearest,
            mip: None,
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::ClampToEdge,
        }
    );
    assert_eq!(t.transform.scale, DVec2::new(1.0, 2.0));
    // The field's word is the use's index in the scene's table of uses.
    let uses = s.texture_uses();
    let words = w.words(|r| penumbra::scene::Scene::texture_use_index(&uses, r));
    assert_eq!(uses[words[0] as usize], t);
    // A plain integer stays one.
    let shaders = json!({
        "floor": {"type": "wgsl", "file": "painted.wgsl", "params": {"t": 7, "c": [1, 1, 1]}},
        "ball": {"type": "phong", "diffuse": [1, 1, 1]}
    });
    let (_d, _p, loaded) = load(&scene(shaders), &[("painted.wgsl", PAINTED.as_bytes())]);
    let Shader::Wgsl(w) = &loaded.scene.shaders[1] else {
        panic!()
    };
    assert_eq!(w.values[0], ParamValue::U32(7));
    assert!(loaded.scene.textures.is_empty());
}

#[test]
fn encoding_linear_loads_the_values_as_they_are_and_is_its_own_texture() {
    let shaders = json!({
        "floor": {"type": "wgsl", "file": "painted.wgsl",
                  "params": {"t": {"texture": "w.png", "encoding": "linear"}, "c": [1, 1, 1]}},
        "ball": {"type": "phong", "diffuse": {"texture": "w.png", "encoding": "srgb"},
                 "specular": {"texture": "w.png"}, "ambient": {"texture": "w.png", "encoding": "linear"}}
    });
    let (_d, _p, loaded) = load(
        &scene(shaders),
        &[("w.png", &png()), ("painted.wgsl", PAINTED.as_bytes())],
    );
    let s = &loaded.scene;
    // The ball's diffuse and specular (sRGB) share one texture, its ambient
    // (linear) is the other, and the floor's parameter shares that one.
    assert_eq!(s.textures.len(), 2, "one file, two encodings");
    let ball = phong(&s.shaders[0]);
    let (srgb, linear) = (
        ball.textures.diffuse.unwrap().texture,
        ball.textures.ambient.unwrap().texture,
    );
    assert_ne!(srgb, linear);
    assert!(s.textures[srgb].srgb && !s.textures[linear].srgb);
    assert_eq!(ball.textures.specular.unwrap().texture, srgb);
    let Shader::Wgsl(w) = &s.shaders[1] else {
        panic!("floor is the wgsl shader")
    };
    let ParamValue::Texture(t) = w.values[0] else {
        panic!("t is a texture: {:?}", w.values)
    };
    assert_eq!(t.texture, linear);
    // The same texels either way; the flag says how the GPU decodes them.
    assert_eq!(s.textures[0].texels, s.textures[1].texels);
    // A watcher reads the file once for both.
    let pngs = loaded
        .files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "png"))
        .count();
    assert_eq!(pngs, 1, "{:?}", loaded.files);
}

// ------------------------------------------------------------ bad input

const FIELD: &str = "shaders.floor.diffuse";

#[test]
fn a_missing_file_names_it() {
    let e = fails(
        &floor_with(json!({"texture": "nope.png"})),
        &[],
        "shaders.floor.diffuse.texture",
        &["no such file", "nope.png"],
    );
    assert!(e.message.contains("nope.png"), "{e}");
}

#[test]
fn corrupt_and_unsupported_files_name_the_file() {
    let mut cut = png();
    cut.truncate(cut.len() - 20);
    fails(
        &floor_with(json!({"texture": "cut.png"})),
        &[("cut.png", &cut)],
        "shaders.floor.diffuse.texture",
        &["cut.png", "corrupt"],
    );
    fails(
        &floor_with(json!({"texture": "text.png"})),
        &[("text.png", b"not an image at all")],
        "shaders.floor.diffuse.texture",
        &["text.png", "not a PNG or JPEG"],
    );
    // A GIF's signature: a format the decoder knows but textures do not take.
    fails(
        &floor_with(json!({"texture": "anim.gif"})),
        &[("anim.gif", b"GIF89a\x01\x00\x01\x00\x00\x00\x00;")],
        "shaders.floor.diffuse.texture",
        &["anim.gif", "must be PNG or JPEG"],
    );
    // A directory is not a file.
    let (dir, path) = write(&floor_with(json!({"texture": "folder.png"})), &[]);
    std::fs::create_dir(dir.path().join("folder.png")).unwrap();
    let e = load_scene(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "shaders.floor.diffuse.texture", "{e}");
    assert!(e.message.contains("not a regular file"), "{e}");
}

#[test]
fn bad_sampler_values_name_their_field() {
    let f = [("w.png", png())];
    let files: Vec<(&str, &[u8])> = f.iter().map(|(n, b)| (*n, b.as_slice())).collect();
    let cases: [(Value, String, &[&str]); 11] = [
        (
            json!({"texture": "w.png", "filter": "linear"}),
            format!("{FIELD}.filter"),
            &["unknown filter \"linear\"", "trilinear"],
        ),
        (
            json!({"texture": "w.png", "filter": 1}),
            format!("{FIELD}.filter"),
            &["nearest"],
        ),
        (
            json!({"texture": "w.png", "wrap": "clamp_to_edge"}),
            format!("{FIELD}.wrap"),
            &["unknown wrap mode \"clamp_to_edge\"", "mirrored_repeat"],
        ),
        (
            json!({"texture": "w.png", "wrap": ["repeat", "tile"]}),
            format!("{FIELD}.wrap[1]"),
            &["unknown wrap mode \"tile\""],
        ),
        (
            json!({"texture": "w.png", "scale": 0}),
            format!("{FIELD}.scale"),
            &["non-zero"],
        ),
        (
            json!({"texture": "w.png", "scale": [1, 2, 3]}),
            format!("{FIELD}.scale"),
            &["two numbers"],
        ),
        (
            json!({"texture": "w.png", "offset": [1, 2]}),
            format!("{FIELD}.offset"),
            &["unknown field `offset`"],
        ),
        (
            json!({"filter": "nearest"}),
            FIELD.to_string(),
            &["missing field `texture`"],
        ),
        (
            json!({"texture": "w.png", "encoding": "sRGB-ish"}),
            format!("{FIELD}.encoding"),
            &["\"srgb\" or \"linear\"", "sRGB-ish"],
        ),
        (
            json!({"texture": "w.png", "encoding": false}),
            format!("{FIELD}.encoding"),
            &["\"srgb\" or \"linear\""],
        ),
        (
            json!({"texture": 3}),
            format!("{FIELD}.texture"),
            &["image file name"],
        ),
    ];
    for (v, field, must) in cases {
        fails(&floor_with(v), &files, &field, must);
    }
    // A colour neither an array nor a texture.
    fails(
        &floor_with(json!("wood.png")),
        &files,
        FIELD,
        &["[r, g, b]", "texture"],
    );
    // Arrays keep their checks.
    fails(
        &floor_with(json!([1, 2])),
        &files,
        FIELD,
        &["invalid length 2"],
    );
    fails(
        &floor_with(json!([1, -2, 0])),
        &files,
        FIELD,
        &["non-negative"],
    );
}

#[test]
fn a_texture_where_no_texture_goes_is_refused_at_its_path() {
    let f = [("w.png", png())];
    let files: Vec<(&str, &[u8])> = f.iter().map(|(n, b)| (*n, b.as_slice())).collect();
    let tex = json!({"texture": "w.png"});
    let mut on_shininess = floor_with(json!([1, 1, 1]));
    on_shininess["shaders"]["floor"]["shininess"] = tex.clone();
    let mut on_light = floor_with(json!([1, 1, 1]));
    on_light["lights"][0]["diffuse"] = tex.clone();
    let mut on_background = floor_with(json!([1, 1, 1]));
    on_background["background"] = tex.clone();
    for (v, field) in [
        (on_shininess, "shaders.floor.shininess"),
        (on_light, "lights[0].diffuse"),
        (on_background, "background"),
    ] {
        fails(&v, &files, field, &["can only be", "phong", "u32 Params"]);
    }
    // A checker has no colours at all.
    let v = scene(json!({
        "floor": {"type": "checker", "size": 1, "even": "ball", "odd": "ball", "diffuse": tex},
        "ball": {"type": "phong", "diffuse": [1, 1, 1]}
    }));
    fails(
        &v,
        &files,
        "shaders.floor.diffuse",
        &["not a field of a checker shader"],
    );
}

#[test]
fn a_texture_for_a_params_field_that_is_not_u32_is_refused() {
    let shaders = json!({
        "floor": {"type": "wgsl", "file": "painted.wgsl",
                  "params": {"t": 0, "c": {"texture": "w.png"}}},
        "ball": {"type": "phong", "diffuse": [1, 1, 1]}
    });
    let png = png();
    fails(
        &scene(shaders),
        &[("w.png", &png), ("painted.wgsl", PAINTED.as_bytes())],
        "shaders.floor.params.c",
        &["`c`", "painted.wgsl", "vec3<f32>", "only a u32 field"],
    );
    // And a bad texture in a u32 field names the field's path.
    let shaders = json!({
        "floor": {"type": "wgsl", "file": "painted.wgsl",
                  "params": {"t": {"texture": "gone.png"}, "c": [1, 1, 1]}},
        "ball": {"type": "phong", "diffuse": [1, 1, 1]}
    });
    fails(
        &scene(shaders),
        &[("painted.wgsl", PAINTED.as_bytes())],
        "shaders.floor.params.t.texture",
        &["no such file", "gone.png"],
    );
}

#[test]
fn texture_files_go_through_the_guard() {
    // --restrict-paths: a texture outside the scene's folder is refused.
    let outer = tempfile::tempdir().unwrap();
    std::fs::write(outer.path().join("out.png"), png()).unwrap();
    let inner = outer.path().join("scene");
    std::fs::create_dir(&inner).unwrap();
    let path = inner.join("scene.json");
    let v = floor_with(json!({"texture": "../out.png"}));
    std::fs::write(&path, v.to_string()).unwrap();
    let opts = LoadOptions {
        restrict_paths: true,
        ..Default::default()
    };
    let e = load_scene(&path, &opts).unwrap_err();
    assert_eq!(e.field, "shaders.floor.diffuse.texture", "{e}");
    assert!(e.message.contains("outside the scene's folder"), "{e}");
    assert!(load_scene(&path, &LoadOptions::default()).is_ok());
    // The memory budget counts the file: one byte short of the scene file
    // and the image file.
    let png_len = png().len() as u64;
    let opts = LoadOptions {
        max_scene_bytes: std::fs::metadata(&path).unwrap().len() + png_len - 1,
        ..Default::default()
    };
    let e = load_scene(&path, &opts).unwrap_err();
    assert_eq!(e.field, "shaders.floor.diffuse.texture", "{e}");
    assert!(e.message.contains("--max-scene-memory"), "{e}");
}

#[test]
fn the_example_scene_loads_with_its_textures() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textured.json");
    let loaded = load_scene(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let s = &loaded.scene;
    assert_eq!(s.textures.len(), 2, "tiles.png and globe.png");
    for t in &s.textures {
        let f = t.file.as_ref().unwrap();
        assert!(loaded.files.contains(f), "{f:?} in {:?}", loaded.files);
        assert!(std::fs::metadata(f).unwrap().len() < 50_000, "{f:?}: small");
    }
    assert!(s
        .shaders
        .iter()
        .any(|sh| matches!(sh, Shader::Wgsl(w) if w.values.iter().any(|v| matches!(v, ParamValue::Texture(_))))));
    assert!(s
        .shaders
        .iter()
        .any(|sh| matches!(sh, Shader::Phong(p) if p.textures.diffuse.is_some())));
}

#[test]
fn a_mesh_without_a_shader_keeps_its_gltf_textures_after_the_scenes_own() {
    let gltf = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let mut v = floor_with(json!({"texture": "w.png"}));
    v["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({"type": "mesh", "file": gltf, "transform": {"translate": [0, 2, 0]}}));
    let (_d, _p, loaded) = load(&v, &[("w.png", &png())]);
    let s = &loaded.scene;
    assert_eq!(s.textures.len(), 2, "w.png, then the box's image");
    assert_eq!((s.textures[0].width, s.textures[0].height), (3, 2));
    let box_object = s.objects.last().unwrap();
    let Shader::MetallicRoughness(m) = &s.shaders[box_object.shader] else {
        panic!("glTF's own material: {:?}", s.shaders[box_object.shader]);
    };
    let t = m
        .textures
        .base_colour
        .expect("the box's base colour texture");
    assert_eq!(t.texture, 1, "moved past the scene's own texture");
    assert_eq!(s.textures[1].width, 211);
    // With a shader of the scene, the material (and its image) is not used.
    let mut v = floor_with(json!({"texture": "w.png"}));
    v["objects"]
        .as_array_mut()
        .unwrap()
        .push(json!({"type": "mesh", "file": gltf, "shader": "floor"}));
    let (_d, _p, loaded) = load(&v, &[("w.png", &png())]);
    assert_eq!(loaded.scene.textures.len(), 1);
    let last = loaded.scene.objects.last().unwrap();
    assert_eq!(last.shader, 1);
    assert!(last.maps.is_none());
}
