//! Hot reload with the staged renderer (issue 13): a user shader file is
//! watched as a shader, an edit recompiles only the pipelines whose files
//! changed (asserted through the reload report), a shading edit reuses the
//! hit records, a broken user shader keeps the last image and the next good
//! save recovers, and a `Params` change reloads the scene to check its JSON.

use std::path::{Path, PathBuf};

use crate::watch_support::*;
use penumbra::render::ShaderSource;

/// A user shader: `base` times the cosine of the light.
const TOON: &str = "// A user shader for the watch tests.
struct Params {
    base: vec3<f32>,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return p.base * l.intensity * max(dot(l.to_light, s.normal), 0.0);
}
";

/// The fixture's sphere with the user shader `toon.wgsl` (`params`: the
/// JSON of its parameters), lit head-on by a white directional light: the
/// centre pixel is `shade`'s value there.
fn user_scene(params: &str) -> String {
    format!(
        r#"{{
  "camera": {{ "position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 64, "height": 48 }},
  "background": [0, 0, 0],
  "shaders": {{ "u": {{ "type": "wgsl", "file": "toon.wgsl", "params": {params} }} }},
  "objects": [ {{ "type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "u" }} ],
  "lights": [ {{ "type": "directional", "direction": [0, 0, -1], "intensity": 1, "ambient": [0, 0, 0], "diffuse": [1, 1, 1], "specular": [1, 1, 1] }} ]
}}"#
    )
}

/// The fixture with its scene switched to the user shader; returns the
/// shader file's path.
fn with_user_shader(fx: &Fixture) -> PathBuf {
    let toon = fx.dir.path().join("toon.wgsl");
    std::fs::write(&toon, TOON).unwrap();
    std::fs::write(&fx.scene, user_scene(r#"{"base": [0.8, 0.3, 0.2]}"#)).unwrap();
    toon
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn a_user_shader_edit_recompiles_only_its_shade_pipeline_and_reuses_the_hits() {
    let fx = Fixture::new();
    let toon = with_user_shader(&fx);
    // The built-ins embedded: user shader files are watched all the same.
    let mut opts = fx.options();
    opts.renderer.shaders = ShaderSource::Embedded;
    let mut w = Running::start(opts);
    assert!(w.reloads[0].errors.is_empty(), "{:?}", w.reloads[0].errors);
    let c0 = fx.centre();
    assert!(c0[0] > 200 && c0[1] > 100, "base [0.8, 0.3, 0.2]: {c0:?}");

    // (b) A real code change in the user's file: a shader change, not a
    // scene change; only its shade pipeline; the hits are reused.
    std::fs::write(
        &toon,
        scale_return(TOON, "fn shade(", "vec3<f32>(0.0, 1.0, 1.0)"),
    )
    .unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(r.changes.shaders && !r.changes.scene, "{}", r.line);
    assert!(r.upload.is_none(), "the upload is kept: {}", r.line);
    let c = r.compile.as_ref().expect("a shader change recompiles");
    assert_eq!(c.recompiled, [shade_name(&toon)], "{}", r.line);
    assert_eq!(r.stages.len(), 2, "{r:#?}");
    assert!(r.stages.iter().all(|s| s.hits_reused), "{r:#?}");
    assert!(r.line.contains("(hits reused)"), "{}", r.line);
    let c1 = fx.centre();
    assert_eq!(c1[0], 0, "red times 0: {c1:?}");
    assert!(c1[1].abs_diff(c0[1]) <= 1, "{c0:?} -> {c1:?}");
    let good = fx.output();

    // (c) A syntax error: the user's file:line:col, the line and a caret;
    // the image on disk stays as it was.
    let broken = scale_return(TOON, "fn shade(", "vec3<f32>(0.0, 1.0, 1.0) +");
    let n = line_of(&broken, "1.0, 1.0) +;");
    std::fs::write(&toon, &broken).unwrap();
    let r = w.next_reload();
    assert_eq!(r.errors.len(), 1, "{r:#?}");
    let e = &r.errors[0];
    let want = format!("{}:{n}:", shade_name(&toon).strip_prefix("shade ").unwrap());
    assert!(e.contains(&want), "error should name {want}: {e}");
    assert!(e.contains("1.0, 1.0) +;") && e.contains('^'), "{e}");
    assert!(r.stages.is_empty(), "{r:#?}");
    assert!(r.line.contains("ERROR"), "{}", r.line);
    assert_eq!(
        fx.output(),
        good,
        "a broken shader must not touch the output"
    );

    // The next good save recovers: a new image.
    std::fs::write(
        &toon,
        scale_return(TOON, "fn shade(", "vec3<f32>(1.0, 0.0, 1.0)"),
    )
    .unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert_eq!(
        r.compile.as_ref().unwrap().recompiled,
        [shade_name(&toon)],
        "{}",
        r.line
    );
    assert_ne!(fx.output(), good, "a new image after the recovery");
    let c2 = fx.centre();
    assert!(c2[0] > 200 && c2[1] == 0, "{c2:?}");

    // A Params change: the uploaded parameters no longer fit, so the scene
    // is reloaded, and its JSON, which lacks the new field, is the error
    // (naming the JSON path); the image stays.
    let with_gain = TOON
        .replace("base: vec3<f32>,", "base: vec3<f32>,\n    gain: f32,")
        .replace("return p.base *", "return p.gain * p.base *");
    std::fs::write(&toon, &with_gain).unwrap();
    let r = w.next_reload();
    assert_eq!(r.errors.len(), 1, "{r:#?}");
    let e = &r.errors[0];
    assert!(
        e.contains("scene.json") && e.contains("shaders.u.params.gain") && e.contains("gain: f32"),
        "{e}"
    );
    assert!(r.stages.is_empty(), "{r:#?}");
    let before = fx.output();
    assert_eq!(fx.centre(), c2);

    // The scene saved with the new field: the new shader renders (its new
    // pipeline, not the one compiled for the old Params).
    std::fs::write(
        &fx.scene,
        user_scene(r#"{"base": [0.8, 0.3, 0.2], "gain": 0.5}"#),
    )
    .unwrap();
    let r = w.reload_until("the scene with gain", |r| r.changes.scene);
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert_ne!(fx.output(), before);
    let c3 = fx.centre();
    // 0.4 linear is 170 in sRGB, 0.8 is 231.
    assert!(c3[0].abs_diff(170) <= 2, "gain 0.5 halves red: {c3:?}");

    // And the user file stays watched as a shader.
    std::fs::write(
        &toon,
        with_gain.replace("p.gain * p.base", "p.gain * p.base * 2.0"),
    )
    .unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(r.changes.shaders && !r.changes.scene, "{}", r.line);
    assert_eq!(
        r.compile.as_ref().unwrap().recompiled,
        [shade_name(&toon)],
        "{}",
        r.line
    );
    assert!(fx.centre()[0] > 225, "{:?}", fx.centre());
}

/// `fn intersect_sphere`'s distance times a factor just above 1: new code
/// for the hit stage's closest-hit and shadow-ray traversals, the same image
/// to the eye.
fn sphere_edited(shaders: &Path, factor: &str) {
    let path = shaders.join("primitives/sphere.wgsl");
    let src = std::fs::read_to_string(&path).unwrap();
    let old = "return select(roots.y, roots.x, roots.x > 0.0);";
    assert!(
        src.contains(old),
        "primitives/sphere.wgsl changed: update the test"
    );
    let new = format!("return select(roots.y, roots.x, roots.x > 0.0) * {factor};");
    std::fs::write(&path, src.replace(old, &new)).unwrap();
}

#[test]
fn a_traversal_edit_recompiles_the_hit_stage_and_traces_again() {
    let fx = Fixture::new();
    let mut w = Running::start(fx.options());
    assert!(w.reloads[0].errors.is_empty(), "{:?}", w.reloads[0].errors);
    // The first render traced its rays.
    assert!(w.reloads[0].stages.iter().all(|s| !s.hits_reused));

    sphere_edited(&fx.shaders, "1.000001");
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert!(r.changes.shaders && !r.changes.scene, "{}", r.line);
    let mut names = r.compile.as_ref().unwrap().recompiled.clone();
    names.sort();
    // One chunk holds the scene's light samples, so the hit stage traces
    // the shadow rays and the frame has no shadow stage to recompile.
    assert_eq!(names, ["hit"], "{}", r.line);
    assert_eq!(r.stages.len(), 2, "{r:#?}");
    assert!(
        r.stages.iter().all(|s| !s.hits_reused),
        "new traversal code traces again: {r:#?}"
    );

    // A shading edit after it reuses the hits of that render.
    std::fs::write(
        fx.shader_path(),
        fx.shader_scaled("vec3<f32>(0.5, 0.5, 0.5)"),
    )
    .unwrap();
    let r = w.next_reload();
    assert!(r.errors.is_empty(), "{:?}", r.errors);
    assert_eq!(
        r.compile.as_ref().unwrap().recompiled,
        [shade_name(&fx.shader_path())],
        "{}",
        r.line
    );
    assert!(r.stages.iter().all(|s| s.hits_reused), "{r:#?}");
}
