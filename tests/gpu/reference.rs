//! The `f64` CPU reference renderer (`penumbra::reference`): against the GPU
//! path on the same scenes, against Embree's independent hit and shadow
//! counts on the bunny benchmark, and end to end through
//! `penumbra render --reference`.
//!
//! # Tolerance
//!
//! The GPU computes in `f32` (relative precision u = 2⁻²⁴ ≈ 6·10⁻⁸), the
//! reference in `f64`. A pixel is a sum of a few terms of magnitude ≤ ~2
//! (premultiplied light colours times falloff), each the product of a few
//! dozen rounded operations; the shininess exponent (≤ 40 here) multiplies
//! the relative error of the lobe's cosine, and positions carry rounding
//! relative to their distance from the eye (≤ ~10 units). That bounds a
//! smooth pixel's difference by roughly 2 · 100 · 40 · u ≈ 5·10⁻⁴; we allow
//! [`TOL`] = 2·10⁻³, still half of one 8-bit step (1/255 ≈ 3.9·10⁻³), so an
//! agreeing pixel encodes to the same or a neighbouring PNG value. Where
//! `f32` and `f64` decide differently — a primary ray within rounding of a
//! silhouette, a shadow ray within rounding of an occluder's edge, a point on
//! a checker boundary — a pixel can differ by a whole term; such pixels lie
//! on edges and must stay below 0.5 % of the image ([`MIN_AGREEING`]). The
//! worst difference and the fraction are printed (`--nocapture`).
//!
//! Measured (lavapipe): showcase 240×135 1 pixel over TOL (9.6·10⁻³, on an
//! edge); area_lights 160×90 13 pixels (checker cells flipping near the
//! horizon, where the plane is far and `f32` positions are coarse, and one
//! light sample's shadow flipping in a penumbra); bunny 256² 5 pixels, at
//! 1024² 67. The bunny's are all grazing light at concave folds: the GPU's
//! shadow ray starts 256 `f32` ulps of the camera-relative position (about
//! 5·10⁻⁵ units here) off the surface, and at light angles of a few degrees
//! to the neighbouring triangle that shifts where the ray meets it by ~10⁻³,
//! past its edge; the exact answer (and the reference) is "in shadow".

use crate::support;

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DVec3, Vec3};
use penumbra::loaders::{self, LoadOptions};
use penumbra::render::{Frame, Image, KernelOptions, Sampler, Sampling};
use penumbra::scene::{Light, LightKind, Object, Phong, Plane, Scene, Shader, Shape, Triangle};

/// Largest per-channel difference of an agreeing pixel (see the module docs).
const TOL: f64 = 2e-3;
/// Least fraction of agreeing pixels.
const MIN_AGREEING: f64 = 0.995;

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

fn load_sized(name: &str, width: u32, height: u32) -> Scene {
    loaders::load_scene(
        &scene_path(name),
        &LoadOptions {
            width: Some(width),
            height: Some(height),
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .scene
}

/// How two images compare.
#[derive(Debug)]
struct Agreement {
    /// Fraction of pixels whose channels (RGB and alpha) all differ by ≤ TOL.
    agreeing: f64,
    /// Largest channel difference over all pixels.
    worst: f64,
    /// Largest channel difference over the agreeing pixels.
    worst_agreeing: f64,
}

fn compare(a: &Image, b: &Image) -> Agreement {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let (mut ok, mut worst, mut worst_ok) = (0usize, 0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let d = (0..4)
            .map(|c| (p[c] as f64 - q[c] as f64).abs())
            .fold(0.0, f64::max);
        assert!(d.is_finite(), "non-finite pixel {p:?} / {q:?}");
        worst = worst.max(d);
        if d <= TOL {
            ok += 1;
            worst_ok = worst_ok.max(d);
        }
    }
    Agreement {
        agreeing: ok as f64 / a.pixels.len() as f64,
        worst,
        worst_agreeing: worst_ok,
    }
}

/// Renders `scene` both ways and checks that they agree; returns both frames.
fn gpu_vs_reference(
    label: &str,
    scene: &Scene,
    kernel: KernelOptions,
    sampling: Sampling,
) -> (Frame, Frame) {
    let g = support::render_with(scene, kernel, sampling);
    let r = penumbra::reference::render(scene, &sampling, kernel.sampler);
    let a = compare(&g.image, &r.image);
    eprintln!(
        "{label}: {:.4} % of pixels within {TOL} (worst there {:.2e}), worst overall {:.3e}; shadow rays GPU {} / reference {}",
        a.agreeing * 100.0,
        a.worst_agreeing,
        a.worst,
        g.stats.shadow_rays,
        r.stats.shadow_rays
    );
    assert!(a.agreeing >= MIN_AGREEING, "{label}: {a:?}");
    assert_eq!(r.stats.passes, g.stats.passes);
    assert_eq!(r.stats.primary_rays, g.stats.primary_rays);
    // Shadow rays are counted the same way; only points within rounding of
    // a light's horizon can count differently.
    let (gs, rs) = (g.stats.shadow_rays as f64, r.stats.shadow_rays as f64);
    assert!(
        (gs - rs).abs() <= 1e-3 * gs.max(1.0),
        "{label}: shadow rays {gs} vs {rs}"
    );
    (g, r)
}

/// Single-sided triangles seen from their back (glTF `doubleSided: false`):
/// the reference skips them for camera rays and keeps them as occluders, as
/// the kernel does.
#[test]
fn single_sided_triangles_match_the_gpu() {
    for (flipped, double_sided) in [(true, false), (false, false), (true, true)] {
        let scene = crate::double_sided::scene(flipped, double_sided);
        gpu_vs_reference(
            &format!("single-sided quad, flipped {flipped}, double-sided {double_sided}"),
            &scene,
            KernelOptions::default(),
            Sampling::default(),
        );
    }
}

fn lambert(rgb: f32) -> Shader {
    Shader::Phong(Phong {
        textures: Default::default(),
        ambient: Vec3::ZERO,
        diffuse: Vec3::splat(rgb),
        specular: Vec3::ZERO,
        shininess: 1.0,
    })
}

/// A white Lambert floor y = 0 seen from straight above (orthographic,
/// x, z in [−1, 1]), a triangle occluder at y = 0.3, a rectangle light 0.6
/// above the floor and a sphere light, both with `samples` per pass. The
/// light is close and large, so every sample's position shows strongly in
/// the pixel (falloff, emitter cosine, and the occluder's shadow).
fn sampling_scene(samples: u32) -> Scene {
    let light = |kind| Light {
        kind,
        intensity: 1.0,
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
    };
    Scene {
        textures: vec![],
        camera: support::top_down(1.0, 48),
        background: Vec3::ZERO,
        shaders: vec![lambert(1.0), lambert(0.5)],
        objects: vec![
            Object {
                maps: Default::default(),
                shape: Shape::Plane(Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Y,
                }),
                shader: 0,
            },
            Object {
                maps: Default::default(),
                shape: Shape::Triangle(Triangle {
                    vertices: [
                        DVec3::new(-0.4, 0.3, -0.2),
                        DVec3::new(0.3, 0.3, -0.4),
                        DVec3::new(0.0, 0.3, 0.5),
                    ],
                }),
                shader: 1,
            },
        ],
        lights: vec![
            light(LightKind::Rect {
                corner: DVec3::new(-0.5, 0.6, -0.5),
                edge1: DVec3::X,
                edge2: DVec3::Z, // X × Z = −Y: emits downwards
                samples,
            }),
            light(LightKind::Sphere {
                center: DVec3::new(0.7, 0.9, 0.6),
                radius: 0.3,
                samples,
            }),
        ],
    }
}

/// With one light sample per pass and 4 jittered passes, each pixel is the
/// mean of 4 pixel positions × 2 light points; they are the same points on
/// both sides only if the sampling port is bit-exact. A different seed (the
/// same sequences shifted elsewhere) must disagree, so the comparison is not
/// trivially true.
#[test]
fn sample_points_match_the_gpu() {
    let scene = sampling_scene(1);
    for (sampler, seed) in [(Sampler::Stratified, 0), (Sampler::Random, 7)] {
        let kernel = KernelOptions {
            sampler,
            ..Default::default()
        };
        let sampling = Sampling {
            spp: 4,
            seed,
            time_budget: None,
        };
        let (g, _) = gpu_vs_reference(&format!("sampling {sampler:?}"), &scene, kernel, sampling);
        let other = penumbra::reference::render(
            &scene,
            &Sampling {
                seed: seed + 1,
                ..sampling
            },
            kernel.sampler,
        );
        let a = compare(&g.image, &other.image);
        eprintln!("  other seed: {:.2} % within {TOL}", a.agreeing * 100.0);
        assert!(a.agreeing < 0.5, "a different seed should disagree: {a:?}");
        assert!(a.worst > 0.05, "{a:?}");
    }
}

#[test]
fn showcase_matches_the_gpu() {
    let scene = load_sized("showcase.json", 240, 135);
    gpu_vs_reference(
        "showcase",
        &scene,
        KernelOptions::default(),
        Sampling::default(),
    );
}

#[test]
fn area_lights_match_the_gpu() {
    let mut scene = load_sized("area_lights.json", 160, 90);
    for l in &mut scene.lights {
        l.kind.set_samples(2);
    }
    let sampling = Sampling {
        spp: 2,
        seed: 3,
        time_budget: None,
    };
    gpu_vs_reference("area_lights", &scene, KernelOptions::default(), sampling);
}

#[test]
fn bunny_matches_the_gpu() {
    let scene = load_sized("bunny_scene.glb", 256, 256);
    gpu_vs_reference(
        "bunny",
        &scene,
        KernelOptions::default(),
        Sampling::default(),
    );
}

/// glTF's metallic-roughness BRDF: metal and dielectric spheres from
/// roughness 0.05 to 1 on a half-metal floor, and two spheres of the
/// specular-glossiness model, under a directional, a point
/// and a spot light of different colours (each light's diffuse colour
/// differs from its specular one, so the split of the BRDF between them is
/// compared too).
#[test]
fn metallic_roughness_matches_the_gpu() {
    let mut shaders = vec![
        r#""floor": {"type": "metallic_roughness", "base_colour": [0.5, 0.5, 0.45], "metallic": 0.5, "roughness": 0.7}"#.to_string(),
    ];
    let mut objects = vec![
        r#"{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"}"#
            .to_string(),
    ];
    // KHR_materials_pbrSpecularGlossiness's model beside them (behind).
    for (i, glossiness) in [0.4, 0.9].iter().enumerate() {
        let name = format!("sg{i}");
        shaders.push(format!(
            r#""{name}": {{"type": "specular_glossiness", "diffuse": [0.2, 0.5, 0.3], "specular": [0.6, 0.4, 0.2], "glossiness": {glossiness}}}"#
        ));
        objects.push(format!(
            r#"{{"type": "sphere", "center": [{}, 0.5, -1.8], "radius": 0.45, "shader": "{name}"}}"#,
            i as f64 * 1.1 - 0.55
        ));
    }
    for (i, roughness) in [0.1, 0.2, 0.5, 1.0].iter().enumerate() {
        for (j, metallic) in [0.0, 1.0].iter().enumerate() {
            let name = format!("m{i}{j}");
            shaders.push(format!(
                r#""{name}": {{"type": "metallic_roughness", "base_colour": [0.9, 0.5, 0.2], "metallic": {metallic}, "roughness": {roughness}}}"#
            ));
            objects.push(format!(
                r#"{{"type": "sphere", "center": [{}, 0.5, {}], "radius": 0.45, "shader": "{name}"}}"#,
                i as f64 * 1.1 - 1.65,
                j as f64 * 1.2 - 0.6
            ));
        }
    }
    let json = format!(
        r#"{{
  "camera": {{"position": [0, 2.5, 4.5], "look_at": [0, 0.3, 0], "up": [0, 1, 0], "fov": 45, "width": 160, "height": 100}},
  "background": [0.05, 0.05, 0.05],
  "shaders": {{ {} }},
  "objects": [ {} ],
  "lights": [
    {{"type": "directional", "direction": [0.4, -1, -0.5], "intensity": 1.5, "ambient": [0, 0, 0], "diffuse": [1, 0.9, 0.8], "specular": [0.8, 0.9, 1]}},
    {{"type": "point", "position": [2, 2, 2], "intensity": 6, "ambient": [0, 0, 0], "diffuse": [0.5, 0.7, 1], "specular": [1, 1, 1]}},
    {{"type": "spot", "position": [-2, 3, 1], "direction": [0.5, -1, -0.3], "inner_angle": 15, "outer_angle": 30, "intensity": 10, "ambient": [0, 0, 0], "diffuse": [1, 0.8, 0.6], "specular": [1, 0.8, 0.6]}}
  ]
}}"#,
        shaders.join(", "),
        objects.join(", ")
    );
    let scene = support::load_json(&json);
    let kinds = |f: fn(&Shader) -> bool| scene.shaders.iter().filter(|s| f(s)).count();
    assert_eq!(kinds(|s| matches!(s, Shader::MetallicRoughness(_))), 9);
    assert_eq!(kinds(|s| matches!(s, Shader::SpecularGlossiness(_))), 2);
    gpu_vs_reference(
        "metallic_roughness",
        &scene,
        KernelOptions::default(),
        Sampling::default(),
    );
}

/// The environment (docs/materials.md, "Environment") on metals and
/// dielectrics of four roughnesses and a Phong floor, with an unshadowed
/// point light: the GPU's environment samples are the reference's (the same
/// mixture, drawn around the same mirror direction of the eye), so the
/// images agree as on the other scenes; seen through a perspective and an
/// orthographic camera (the eye direction is per pixel in one, the view
/// direction in the other).
/// glTF's occlusionTexture, scaling the environment's light and not the
/// point light's: the reference applies the same factor.
#[test]
fn occlusion_matches_the_gpu() {
    for strength in [1.0, 0.5] {
        let scene = crate::occlusion::scene(crate::occlusion::Lights::Both, Some(strength));
        gpu_vs_reference(
            &format!("occlusion, strength {strength}"),
            &scene,
            KernelOptions::default(),
            Sampling::default(),
        );
    }
}

/// KHR_materials_unlit's vertex colours: the reference scales the emission
/// by them as the GPU does, and only where the maps say so.
#[test]
fn unlit_vertex_colours_match_the_gpu() {
    for by_colour in [true, false] {
        let scene = crate::unlit_colours::scene(by_colour);
        let (g, _) = gpu_vs_reference(
            &format!("unlit colours {by_colour}"),
            &scene,
            KernelOptions::default(),
            Sampling::default(),
        );
        assert!(g.image.pixels.iter().any(|p| p[2] > 0.1));
    }
}

#[test]
fn environment_matches_the_gpu() {
    environment_chart_vs_reference("environment", r#""fov": 45"#);
    environment_chart_vs_reference(
        "environment, orthographic",
        r#""projection": "orthographic", "half_height": 2"#,
    );
}

/// The chart of [`environment_matches_the_gpu`] with camera projection
/// `projection` (JSON members), GPU against the reference.
fn environment_chart_vs_reference(label: &str, projection: &str) {
    let mut shaders = vec![
        r#""floor": {"type": "phong", "ambient": [0, 0, 0], "diffuse": [0.4, 0.4, 0.35], "specular": [0.2, 0.2, 0.2], "shininess": 20}"#.to_string(),
    ];
    let mut objects = vec![
        r#"{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "shader": "floor"}"#
            .to_string(),
    ];
    for (i, roughness) in [0.1, 0.2, 0.5, 1.0].iter().enumerate() {
        for (j, metallic) in [0.0, 1.0].iter().enumerate() {
            let name = format!("m{i}{j}");
            shaders.push(format!(
                r#""{name}": {{"type": "metallic_roughness", "base_colour": [0.9, 0.5, 0.2], "metallic": {metallic}, "roughness": {roughness}}}"#
            ));
            objects.push(format!(
                r#"{{"type": "sphere", "center": [{}, 0.5, {}], "radius": 0.45, "shader": "{name}"}}"#,
                i as f64 * 1.1 - 1.65,
                j as f64 * 1.2 - 0.6
            ));
        }
    }
    let json = format!(
        r#"{{
  "camera": {{"position": [0, 2.5, 4.5], "look_at": [0, 0.3, 0], "up": [0, 1, 0], {projection}, "width": 120, "height": 75}},
  "shaders": {{ {} }},
  "objects": [ {} ],
  "lights": [
    {{"type": "environment", "up": [0.1, 1, 0.2], "samples": 8, "intensity": 1.5, "diffuse": [1, 0.9, 0.8], "specular": [1, 0.9, 0.8]}},
    {{"type": "point", "position": [2, 2, 2], "intensity": 3, "ambient": [0, 0, 0], "diffuse": [0.5, 0.7, 1], "specular": [1, 1, 1]}}
  ]
}}"#,
        shaders.join(", "),
        objects.join(", ")
    );
    let scene = support::load_json(&json);
    assert!(matches!(
        scene.lights[0].kind,
        LightKind::Environment { samples: 8, .. }
    ));
    let sampling = Sampling {
        spp: 2,
        seed: 5,
        time_budget: None,
    };
    gpu_vs_reference(label, &scene, KernelOptions::default(), sampling);
}

/// The benchmark scene at 1024×1024 against Embree's figures (see
/// tests/gpu/bunny.rs, which separates ground and bunny the same way):
/// 858,452 primary rays hit (149,894 the bunny), and 31,540 ground points are
/// blocked from the light. This checks the reference without our GPU.
#[test]
fn bunny_counts_match_embree() {
    let scene = support::tagged_bunny_scene();
    let frame = penumbra::reference::render(&scene, &Sampling::default(), Default::default());
    assert_eq!(frame.stats.primary_rays, 1024 * 1024);
    let px = &frame.image.pixels;
    let [bunny, ground, _, ground_dark] = support::bunny_counts(&frame.image);
    eprintln!(
        "reference 1024²: bunny {bunny}, ground {ground}, blocked ground {ground_dark}, {:.2} s",
        frame.stats.timings.render.as_secs_f64()
    );
    assert_eq!(bunny + ground, px.iter().filter(|p| p[3] == 1.0).count());
    assert!(
        (bunny + ground).abs_diff(858_452) <= 2,
        "hits {}",
        bunny + ground
    );
    assert!(bunny.abs_diff(149_894) <= 2, "bunny hits {bunny}");
    assert!(
        ground_dark.abs_diff(31_540) <= 2,
        "blocked ground points {ground_dark}"
    );
}

fn penumbra_cmd(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .output()
        .expect("run penumbra")
}

#[test]
fn cli_reference_writes_the_image_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ref.png");
    let scene = scene_path("showcase.json");
    let o = penumbra_cmd(&[
        "render",
        "--reference",
        scene.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "36",
        "--spp",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    let img = image::open(&out).expect("PNG written").to_rgba8();
    assert_eq!(img.dimensions(), (64, 36));
    // The same frame through the library, encoded the same way.
    let s = load_sized("showcase.json", 64, 36);
    s.validate().unwrap();
    let sampling = Sampling {
        spp: 2,
        ..Default::default()
    };
    let frame = penumbra::reference::render(&s, &sampling, Default::default());
    let expected = dir.path().join("lib.png");
    penumbra::output::write_image(&expected, &frame.image).unwrap();
    assert_eq!(img, image::open(&expected).unwrap().to_rgba8());
    // One summary line in the GPU path's style, rays counted the same way.
    let line = stdout
        .lines()
        .find(|l| l.starts_with("CPU reference (f64): "))
        .unwrap_or_else(|| panic!("{stdout}"));
    let rays = frame.stats.rays();
    let want = format!(
        "CPU reference (f64): 64x36, 2 spp, {rays} rays ({} primary + {} shadow) |",
        64 * 36 * 2,
        frame.stats.shadow_rays
    );
    assert!(line.starts_with(&want), "{line}\nwant {want}");
    assert!(line.contains("Mrays/s"), "{line}");
}

#[test]
fn cli_reference_bad_input_errors_as_the_gpu_path() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, r#"{"camera": {"position": [0, 0, 1]}}"#).unwrap();
    let missing = dir.path().join("missing.json");
    let unwritable = dir.path().join("no/such/dir/x.png");
    for (scene, out) in [
        (&bad, &out),
        (&missing, &out),
        (&scene_path("showcase.json"), &unwritable),
    ] {
        let args = |reference: bool| {
            let mut a = vec![
                "render",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ];
            if reference {
                a.push("--reference");
            }
            a.into_iter().map(String::from).collect::<Vec<_>>()
        };
        let run = |reference: bool| {
            let a = args(reference);
            penumbra_cmd(&a.iter().map(String::as_str).collect::<Vec<_>>())
        };
        let (with, without) = (run(true), run(false));
        assert_eq!(
            with.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&with.stderr)
        );
        assert_eq!(without.status.code(), Some(1));
        let err = String::from_utf8_lossy(&with.stderr);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err, String::from_utf8_lossy(&without.stderr));
        assert!(!out.exists());
    }
    // Options of the GPU only are refused, not silently ignored.
    let scene = scene_path("showcase.json");
    let o = penumbra_cmd(&[
        "render",
        scene.to_str().unwrap(),
        "--reference",
        "--device",
        "0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--device"));
}
